// SPDX-License-Identifier: MIT
// Structural checks of a 3D Tiles tileset as citymesh writes it (`citymesh check`, tests).
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <utility>
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
  /// Metres of edges two leaves share along their borders (each such edge once).
  double seam_length = 0;
  /// Metres of those seams missing from the border of a coarser tile drawn beside one of the
  /// two leaves (summed over such tiles): gaps a viewer shows between levels of detail. The
  /// export keeps tile borders when it simplifies, so only a parent past its triangle cap,
  /// simplified with free borders, has any. Reported, not an error.
  double crack_length = 0;
  /// The tiles with some crack length (glb file, metres), longest first.
  std::vector<std::pair<std::string, double>> cracked_tiles;
  [[nodiscard]] bool ok() const { return errors.empty(); }
};

/// Checks `path` (a tileset.json, or a folder holding one) and everything it references:
/// JSON structure (asset, geometric errors never 0 on a parent and never growing towards the
/// leaves, bounding volumes, refine, transform), content files present inside the folder,
/// external tilesets (no cycles, bounded size), and every glb: header, glTF JSON, Draco
/// required when used, accessor bounds, decoded mesh (triangle and vertex counts, positions
/// within accessor bounds and the tile's box, feature ids within the acquisition table), and
/// measures the cracks between levels of detail (TilesetCheckReport::crack_length).
/// Problems are collected, not thrown; only an unreadable starting point throws InputError.
TilesetCheckReport check_tileset(const std::filesystem::path& path, const TilesetCheckParams& params = {});

}  // namespace citymesh
