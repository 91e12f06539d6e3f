// SPDX-License-Identifier: MIT
// Structural checks of a 3D Tiles tileset as citymesh writes it (`citymesh check`, tests).
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace citymesh {

struct TilesetCheckParams {
  std::uint64_t max_json_bytes = 512 * 1024;  ///< a tileset file larger than this is an error
  double box_tolerance = 0.01;                ///< metres: content may exceed its box by this much
};

struct TilesetCheckReport {
  std::vector<std::string> errors;  ///< "<file>: <where>: <what>"
  std::size_t tiles = 0, glb_files = 0, json_files = 0, levels = 0;
  std::uint64_t triangles = 0;       ///< in every content
  std::uint64_t leaf_triangles = 0;  ///< in the contents of tiles without children
  std::uint64_t glb_bytes = 0, json_bytes = 0;
  [[nodiscard]] bool ok() const { return errors.empty(); }
};

/// Checks `path` (a tileset.json, or a folder holding one) and everything it references:
/// JSON structure (asset, geometric errors never 0 on a parent and never growing towards the
/// leaves, bounding volumes, refine, transform), content files present inside the folder,
/// external tilesets (no cycles, bounded size), and every glb: header, glTF JSON, Draco
/// required when used, accessor bounds, decoded mesh (triangle and vertex counts, positions
/// within accessor bounds and the tile's box, feature ids within the acquisition table).
/// Problems are collected, not thrown; only an unreadable starting point throws InputError.
TilesetCheckReport check_tileset(const std::filesystem::path& path, const TilesetCheckParams& params = {});

}  // namespace citymesh
