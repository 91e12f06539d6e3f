// SPDX-License-Identifier: MIT
// Putting the tiles' results together: the merged mesh of every tile's selected owned
// triangles, and (when asked) the change step's labels of every input triangle.
#pragma once

#include <filesystem>
#include <optional>
#include <string_view>
#include <vector>

#include "citymesh/change/detect.h"
#include "citymesh/mosaic/merged_mesh.h"
#include "pair_spill.h"
#include "tile_job.h"

namespace citymesh::app {

/// What the assembly counts of one tile's result, without its labels, pairs or pieces: all a
/// rank that did not read the result needs of it (an MPI rank reads and files it).
struct TileTally {
  std::uint64_t owned = 0, candidates = 0, seen_through = 0, filled = 0, fill_left_out = 0;
  ChangeStats change{};
  double seconds_read = 0, seconds_detect = 0, seconds_mosaic = 0;
};

/// The tally of `result`. Throws ProcessingError naming the tile when one of its labels is of
/// a triangle the store does not hold.
TileTally tally_of(const TileResult& result, const TileStore& store);

class TileAssembly {
 public:
  /// With a `pairs_dir`, also gathers every input triangle's labels and the consistent pairs,
  /// both spilled to files in that folder (removed with the assembly): memory holds one
  /// acquisition's labels at a time, when labels() expands them.
  TileAssembly(const TileStore& store, std::optional<std::filesystem::path> pairs_dir);

  /// Takes one tile's result (any order: the output does not depend on it).
  void add(TileResult result);
  /// Counts a tile whose result was read elsewhere (tally_of): only without labels, which
  /// need the result itself. Tiles are added once each, by add() or by this.
  void add_tally(const TileTally& tally);

  /// The selected triangles sorted by (acquisition, triangle index), with their global ids;
  /// vertices shared within an acquisition across tiles. Hands over the tiles' pieces: they
  /// are freed once merged (the seam pass then has their memory), so it is called once.
  [[nodiscard]] MergedMesh take_merged();

  /// Acquisition k's labels as the change step gives them (the result's index holds that
  /// acquisition only; no pairs). Only with labels; throws ProcessingError when the tiles did
  /// not label every input triangle.
  [[nodiscard]] ChangeResult labels(std::size_t k) const { return labels(k, 0, triangle_count(k)); }
  /// The labels of its triangles [begin, end) only (the result's triangle 0 is `begin`).
  [[nodiscard]] ChangeResult labels(std::size_t k, std::uint64_t begin, std::uint64_t end) const;
  /// Acquisition k's input triangles.
  [[nodiscard]] std::uint64_t triangle_count(std::size_t k) const { return index_.offsets[k + 1] - index_.offsets[k]; }

  /// Writes the consistent pairs, sorted and unique, as `magic` records to `path`; returns
  /// how many. Only with labels.
  std::uint64_t write_pairs(const std::filesystem::path& path, std::string_view magic) const;

  [[nodiscard]] std::uint64_t owned() const { return owned_; }
  [[nodiscard]] std::uint64_t candidates() const { return candidates_; }
  /// Owned triangles with each mosaic note (MosaicNote): the whole run's counts, each
  /// triangle counted once, by the tile that owns it.
  [[nodiscard]] std::uint64_t seen_through() const { return seen_through_; }
  [[nodiscard]] std::uint64_t filled() const { return filled_; }
  [[nodiscard]] std::uint64_t fill_left_out() const { return fill_left_out_; }
  /// The change step's figures summed over the tiles: a triangle copied into several tiles
  /// (halo, empty space) counts in each, and the seconds are each tile's, added up.
  [[nodiscard]] const ChangeStats& change_stats() const { return change_; }

 private:
  /// The index of a label's first_seen or last_seen among the dates met so far.
  std::uint16_t date_index(std::int64_t ms);
  void check_labelled() const;
  /// Throws ProcessingError naming the tile unless triangle t of acquisition a is in the store.
  void check_in_store(const TileResult& result, std::uint32_t a, std::uint32_t t) const;
  /// Adds a tile's tally to the run's figures.
  void count(const TileTally& tally);
  /// Spills a tile's labels, refuted copies and pairs (only with labels).
  void spill_labels(const TileResult& result);
  /// Spills the copies a tile found refuting, for labels() to raise their `refutes`.
  void spill_refuted(const TileResult& result);

  const TileStore& store_;
  GlobalTriangles index_;
  std::vector<TilePiece> pieces_;
  // Labels, per input triangle: state | kept << 2 | sustainable << 3 | refutes << 4, and
  // first_seen and last_seen as indices into dates_ms_; on disk by acquisition (in the pairs'
  // folder, which pairs_ makes and removes: declared first, it outlives labels_).
  std::vector<std::int64_t> dates_ms_;
  std::optional<PairSpill> pairs_;
  std::optional<LabelSpill> labels_;
  std::uint64_t owned_ = 0, candidates_ = 0, seen_through_ = 0, filled_ = 0, fill_left_out_ = 0;
  ChangeStats change_;
};

}  // namespace citymesh::app
