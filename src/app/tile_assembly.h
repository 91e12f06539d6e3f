// SPDX-License-Identifier: MIT
// Putting the tiles' results together: the merged mesh of every tile's selected owned
// triangles, and (when asked) the change step's labels of every input triangle.
#pragma once

#include <optional>
#include <vector>

#include "citymesh/change/detect.h"
#include "citymesh/mosaic/merged_mesh.h"
#include "tile_job.h"

namespace citymesh::app {

class TileAssembly {
 public:
  /// `labels`: also gather the per-triangle labels and consistent pairs of every acquisition.
  TileAssembly(const TileStore& store, bool labels);

  /// Takes one tile's result (any order: the output does not depend on it).
  void add(TileResult result);

  /// The selected triangles sorted by (acquisition, triangle index), with their global ids;
  /// vertices shared within an acquisition across tiles. Hands over the tiles' pieces: they
  /// are freed once merged (the seam pass then has their memory), so it is called once.
  [[nodiscard]] MergedMesh take_merged();

  /// The labels as the change step gives them for the whole input (consistent pairs sorted,
  /// unique; statistics: triangle and pair counts). Only with `labels`.
  [[nodiscard]] ChangeResult change() const;

  [[nodiscard]] std::uint64_t owned() const { return owned_; }
  [[nodiscard]] std::uint64_t candidates() const { return candidates_; }
  /// Owned triangles with each mosaic note (MosaicNote): the whole run's counts, each
  /// triangle counted once, by the tile that owns it.
  [[nodiscard]] std::uint64_t seen_through() const { return seen_through_; }
  [[nodiscard]] std::uint64_t filled() const { return filled_; }
  [[nodiscard]] std::uint64_t fill_left_out() const { return fill_left_out_; }

 private:
  const TileStore& store_;
  bool labels_;
  GlobalTriangles index_;
  std::vector<TilePiece> pieces_;
  std::optional<ChangeResult> change_;
  std::uint64_t owned_ = 0, candidates_ = 0, seen_through_ = 0, filled_ = 0, fill_left_out_ = 0;
};

}  // namespace citymesh::app
