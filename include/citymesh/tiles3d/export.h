// SPDX-License-Identifier: MIT
// Writing the output mesh as an OGC 3D Tiles 1.1 tileset of Draco-compressed glb tiles with
// levels of detail, placed on the globe (docs/3d-tiles.md).
#pragma once

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

#include "citymesh/core/mesh.h"
#include "citymesh/encode/glb.h"
#include "citymesh/geo/crs.h"
#include "citymesh/tiler/tile_grid.h"
#include "citymesh/tiles3d/tile_tree.h"

namespace citymesh {

struct TilesetExportParams {
  std::filesystem::path dir;  ///< replaced as a whole once every file is written
  TileGridParams grid;        ///< the leaves are the tiles of this grid (the run's tiling)
  double tolerance = 0.001;   ///< metres: the largest position error Draco quantization may add
  std::vector<GlbAcquisition> acquisitions;  ///< feature id k names acquisition k
  TileTreeParams tree;
  std::size_t max_tiles_per_file = 341;  ///< per tileset JSON file; deeper tiles go to external tilesets
  bool draco = true;
  int draco_speed = 5;
};

struct TilesetExportStats {
  std::size_t tiles = 0, leaves = 0, levels = 0, json_files = 0;
  std::uint64_t leaf_triangles = 0, all_triangles = 0, glb_bytes = 0;
  int position_bits = 0;
  double quantization_step = 0.0;  ///< metres
  Geodetic origin;                 ///< of the local east-north-up frame
  double seconds = 0.0;
};

/// The output mesh to export: positions in the project CRS (mesh origin + floats), and per
/// triangle its source acquisition (-1: none, e.g. stitching) for the feature ids.
struct TilesetSource {
  const Mesh& mesh;
  std::span<const std::int32_t> source_acq;
  const Crs& crs;  ///< needs a vertical datum
};

/// Writes <dir>/tileset.json, external tilesets and one glb per tile. Vertices are converted
/// to a local east-north-up frame at the centre of the output (ECEF through geodetic
/// coordinates), quantized on one lattice shared by every tile so that equal vertices decode
/// bit-identically in neighbouring tiles. Throws ConfigError when the tolerance is too fine
/// for the output's extent, OutputError when a file cannot be written.
TilesetExportStats export_tileset(const TilesetSource& source, const TilesetExportParams& params);

/// The leaf (grid tile) of each triangle: the tile containing its centroid.
std::vector<TileKey> leaf_keys(const Mesh& mesh, const TileGrid& grid);

}  // namespace citymesh
