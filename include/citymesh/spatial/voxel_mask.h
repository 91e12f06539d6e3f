// SPDX-License-Identifier: MIT
// A set of voxels, given as boxes, that answers one question fast: does this box touch any of
// them? The empty-space grids use it to mark only the places some triangle will ask about.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "citymesh/spatial/voxel_box.h"

namespace citymesh {

/// Blocks of 8 x 8 x 8 voxels, one bit each, found through a dense index over the boxes'
/// extent in blocks. A mask may hold more voxels than it was given, never fewer: when the
/// index would pass `max_blocks` entries (boxes scattered far apart), it holds every voxel.
class VoxelMask {
 public:
  static constexpr std::uint64_t kDefaultMaxBlocks = std::uint64_t{1} << 22;  ///< a 16 MB index

  /// The mask that holds every voxel.
  VoxelMask() = default;
  /// The voxels of every box (each box lo <= hi on every axis).
  explicit VoxelMask(std::span<const VoxelBox> boxes, std::uint64_t max_blocks = kDefaultMaxBlocks);

  /// True when a voxel of `box` is in the mask.
  [[nodiscard]] bool any_in(const VoxelBox& box) const;
  [[nodiscard]] bool holds_everything() const { return everything_; }
  /// Blocks holding at least one voxel.
  [[nodiscard]] std::size_t blocks() const { return rows_.size(); }

 private:
  static constexpr std::uint32_t kNoBlock = UINT32_MAX;
  /// One byte per row of 8 voxels along x, rows indexed by y + 8 z.
  using Block = std::array<std::uint8_t, 64>;

  [[nodiscard]] std::size_t cell(std::int64_t bx, std::int64_t by, std::int64_t bz) const;
  void add(const VoxelBox& box);

  bool everything_ = true;
  std::array<std::int64_t, 3> origin_{};  ///< the first block on each axis
  std::array<std::int64_t, 3> extent_{};  ///< blocks on each axis
  std::vector<std::uint32_t> block_of_;   ///< per cell of the index: its block, or kNoBlock
  std::vector<Block> rows_;
};

}  // namespace citymesh
