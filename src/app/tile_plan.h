// SPDX-License-Identifier: MIT
// Which tiles wait for which (the seam rule of tile_job.h: a tile sees the decisions of its
// neighbours of earlier phases), and how tiles are split into subsets for schedulers without MPI.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "citymesh/tiler/tiler.h"

namespace citymesh::app {

/// The tiles (indices into store.tiles) that tile `k` waits for: its neighbours (sides and
/// corners) of earlier phases, in index order.
std::vector<std::size_t> tile_dependencies(const TileStore& store, std::size_t k);

/// Estimated peak bytes of a tile in flight per triangle it holds (all roles): meshes, change
/// step (~180 B) and mosaic, measured on the default street (docs/tiling.md).
inline constexpr std::uint64_t kBytesPerTileTriangle = 900;

/// The estimated peak bytes of `tile` while it is processed: what the memory budget counts.
std::uint64_t tile_memory_estimate(const TileContents& tile);

/// The tiles among `tiles` (indices into store.tiles) whose estimate alone exceeds `budget`,
/// largest first: each runs alone and may take the process past the budget.
std::vector<std::size_t> tiles_over_budget(const TileStore& store, const std::vector<std::size_t>& tiles,
                                           std::uint64_t budget);

/// One part of a run split for a scheduler: "i/N", 1 <= i <= N.
struct Subset {
  std::size_t index = 1, count = 1;
  /// Parses "i/N"; throws UsageError naming the text otherwise.
  static Subset parse(const std::string& text);
  [[nodiscard]] std::string name() const;
};

/// The tiles subset `subset` owns: consecutive tiles in key order (column strips, so that few
/// of their dependencies lie in other subsets) holding about 1/N of the store's triangles.
/// Every tile is in exactly one subset; a subset may be empty when N exceeds the tiles.
std::vector<std::size_t> subset_tiles(const TileStore& store, const Subset& subset);

/// `tiles` and every tile they wait for, transitively: what a subset must have before its
/// own tiles can run. Sorted.
std::vector<std::size_t> with_dependencies(const TileStore& store, const std::vector<std::size_t>& tiles);

}  // namespace citymesh::app
