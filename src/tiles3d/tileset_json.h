// SPDX-License-Identifier: MIT
// tileset.json (3D Tiles 1.1) for a tile tree, split into external tilesets so that no file
// holds more than a bounded number of tiles.
#pragma once

#include <array>
#include <string>
#include <utility>
#include <vector>

#include "citymesh/tiles3d/tile_tree.h"

namespace citymesh {

struct TilesetJsonParams {
  std::array<double, 16> transform{};    ///< root: local frame -> ECEF, column-major
  std::size_t max_tiles_per_file = 341;  ///< >= 5
  double box_margin = 0.0;               ///< metres added around every bounding box
  double min_half_extent = 0.01;         ///< metres: boxes are never flat
  std::string tileset_version;           ///< asset.tilesetVersion of every file (empty: none)
};

/// (file name, JSON text) of "tileset.json" (first) and every external tileset. Content of
/// tile n is "<name>.glb"; tiles with no triangles have no content.
std::vector<std::pair<std::string, std::string>> tileset_json_files(const TileTree& tree,
                                                                    const TilesetJsonParams& params);

}  // namespace citymesh
