// SPDX-License-Identifier: MIT
// Cracks between the tiles of a tileset (private to tiles3d): where a coarser tile no longer
// meets the finer tiles beside it. Used by check_tileset.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <span>
#include <utility>
#include <vector>

#include "citymesh/core/mesh.h"

namespace citymesh::tiles3d_detail {

/// What count() found: seams are the edges two leaves share along their borders; a crack is
/// a seam between a tile's leaves and a leaf outside them that the tile's own mesh does not
/// have as an open edge (a viewer drawing that tile beside that leaf shows a gap there).
struct TileCracks {
  std::uint64_t seam_edges = 0;
  double seam_length = 0;
  std::uint64_t crack_edges = 0;  ///< (seam, tile) pairs
  double crack_length = 0;        ///< metres, summed over the tiles
  std::vector<std::pair<std::uint32_t, double>> by_tile;  ///< (tile, crack length), longest first
};

/// A tile's decoded content, in the tileset's frame.
struct TileContent {
  std::vector<Vec3f> positions;
  std::vector<Triangle> triangles;
};

/// Gives tile `tile`'s content again (count() asks only for the few tiles it needs).
using TileContentSource = std::function<TileContent(std::uint32_t tile)>;

/// The tiles of a tileset as a tree and the open edges of each content, keyed by vertex
/// position: the export puts every tile's vertices on one lattice, so a vertex has the same
/// float coordinates in every tile that holds it, whatever the Draco vertex order.
class TileCrackCounter {
 public:
  static constexpr std::uint32_t kNoParent = UINT32_MAX;

  /// A new tile under `parent` (kNoParent: a root); returns its id.
  std::uint32_t add_tile(std::uint32_t parent);
  /// Tile `tile`'s decoded content, in the tileset's frame (its open edges are kept).
  void set_content(std::uint32_t tile, std::span<const Vec3f> positions, std::span<const Triangle> triangles);
  /// Leaves are the tiles with content and no child tile. A seam missing from a tile's open
  /// edges may still be one of its inner edges (where more than two triangles meet): the
  /// tile covers it, no crack. `reload` gives the content of the tiles where that must be
  /// told, so that only open edges are held for every tile.
  [[nodiscard]] TileCracks count(const TileContentSource& reload) const;

 private:
  /// An edge by its two corners' coordinate bits, the smaller corner first.
  using EdgeKey = std::array<std::uint32_t, 6>;
  struct Tile {
    std::uint32_t parent = kNoParent;
    bool has_content = false;
    std::uint32_t children = 0;
    std::vector<EdgeKey> open;  ///< sorted
  };
  /// Every edge of the triangles once per use, sorted (an edge of one corner quantized onto
  /// the next is none).
  static std::vector<EdgeKey> edges_of(std::span<const Vec3f> positions, std::span<const Triangle> triangles);
  /// The tile and its ancestors, nearest first.
  [[nodiscard]] std::vector<std::uint32_t> chain(std::uint32_t tile) const;
  static double length(const EdgeKey& e);

  std::vector<Tile> tiles_;
};

}  // namespace citymesh::tiles3d_detail
