// SPDX-License-Identifier: MIT
// Which tiles wait for which (the seam rule of tile_job.h: a tile sees the decisions of its
// neighbours of earlier phases), and how tiles are split into subsets for schedulers without MPI.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "citymesh/tiler/tiler.h"

namespace citymesh::app {

/// The tiles (indices into store.tiles) that tile `k` waits for: its neighbours (sides and
/// corners) of earlier phases, in index order.
std::vector<std::size_t> tile_dependencies(const TileStore& store, std::size_t k);

/// Per store tile, digests of what its result depends on.
struct TileDigests {
  /// `inputs`, the indices of the acquisitions it holds and the digests of its dependencies
  /// (whose decisions it keeps): a result is reused only under the digest it was written
  /// with, so an added or rewritten acquisition redoes the tiles it reaches and, along the
  /// dependencies, their later-phase neighbours are looked at again (kept when the decisions
  /// they keep did not change, renumbered when a pass delivered late renumbered theirs:
  /// tile_stage).
  std::vector<std::uint64_t> result;
  /// The tile's own inputs: `settings` (the run's result-affecting keys), the tile's key and
  /// the identities of the acquisitions it holds triangles of (RunFingerprints::identities,
  /// with the tile's counts), in their order but not by index.
  std::vector<std::uint64_t> inputs;
};

/// The digests of every store tile. Throws ProcessingError when the store holds more
/// acquisitions than `identities` gives.
TileDigests tile_digests(const TileStore& store, std::uint64_t settings, std::span<const std::uint64_t> identities);

/// The order in which the work schedule takes ready tiles (higher first), per tile of `tiles`:
/// largest first (triangles held: big tiles do not end a run alone), but every tile of this
/// process's own before any of `theirs` (per store tile, or empty: all own), the tiles of
/// other subsets that this one waits for. Those are left for their owners as long as this
/// process has work of its own, and skipped when their result has appeared meanwhile.
std::vector<std::uint64_t> tile_priorities(const TileStore& store, const std::vector<std::size_t>& tiles,
                                           std::span<const std::uint8_t> theirs);

/// Estimated peak bytes of a tile in flight per triangle it holds (all roles): meshes, change
/// step (~180 B) and mosaic, measured on the default street (docs/tiling.md).
inline constexpr std::uint64_t kBytesPerTileTriangle = 900;

/// The estimated peak bytes of `tile` while it is processed: what the memory budget counts.
std::uint64_t tile_memory_estimate(const TileContents& tile);
/// Whether `tile` is estimated above `budget`: such a tile runs alone, and its mosaic solves
/// with the least memory.
inline bool tile_over_budget(const TileContents& tile, std::uint64_t budget) {
  return tile_memory_estimate(tile) > budget;
}

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

/// The tiles of each of `count` subsets (indices into store.tiles, each sorted): compact
/// blocks of the grid of about equal cost (triangles held), cut in halves of the subset count
/// across the longer side, recursively, so that their borders, across which a subset redoes
/// the tiles it waits for, stay short. Every tile is in exactly one subset; a subset may be
/// empty when `count` exceeds the tiles.
std::vector<std::vector<std::size_t>> all_subsets(const TileStore& store, std::size_t count);

/// The tiles subset `subset` owns: all_subsets(store, subset.count)[subset.index - 1],
/// worked out alone (any subset count is cheap).
std::vector<std::size_t> subset_tiles(const TileStore& store, const Subset& subset);

/// `tiles` and every tile they wait for, transitively: what a subset must have before its
/// own tiles can run. Sorted.
std::vector<std::size_t> with_dependencies(const TileStore& store, const std::vector<std::size_t>& tiles);

}  // namespace citymesh::app
