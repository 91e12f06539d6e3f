// SPDX-License-Identifier: MIT
// Internal to the mosaic module: the sources a seam part's stitching reads, named by their
// rank among them for the seam pass's cache. A pass delivered late renumbers the passes after
// it by time; a part it does not reach then holds the same sources in the same order under
// other numbers, and is found in the cache under their ranks all the same.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "part_cut.h"

namespace citymesh::mosaic_detail {

class SourceRanks {
 public:
  /// The sources of `own` and of the pieces `around` it: those of their input vertices
  /// (input_vertex_source of their keys) and input triangles (ids and source_acq).
  SourceRanks(const KeyedPiece& own, std::span<const Neighbour> around);

  /// Whether each source is its own rank (the sources are 0 to n-1): nothing to rename.
  [[nodiscard]] bool identity() const { return identity_; }
  /// The sources, ascending: the source of rank r is sources()[r].
  [[nodiscard]] std::span<const std::uint32_t> sources() const { return sources_; }

  /// `piece` with each source named by its rank; nothing when it holds a source not read.
  [[nodiscard]] std::optional<KeyedPiece> to_ranks(const KeyedPiece& piece) const;
  /// `piece` with each rank named by its source (the inverse of to_ranks); nothing when it
  /// holds a rank past the sources.
  [[nodiscard]] std::optional<KeyedPiece> from_ranks(const KeyedPiece& piece) const;

 private:
  std::vector<std::uint32_t> sources_;
  bool identity_ = true;
};

}  // namespace citymesh::mosaic_detail
