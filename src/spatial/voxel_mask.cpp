// SPDX-License-Identifier: MIT
#include "citymesh/spatial/voxel_mask.h"

#include <algorithm>
#include <limits>

namespace citymesh {

namespace {

constexpr int kBlockShift = 3;  ///< blocks of 8 voxels a side
constexpr std::int32_t kInBlock = 7;

/// The block of voxel v: a floor division, negative voxels included.
std::int64_t block_of_voxel(std::int32_t v) { return v >> kBlockShift; }

/// The bits of voxels lo..hi (within one row of 8, both 0..7).
std::uint8_t row_bits(std::int32_t lo, std::int32_t hi) {
  return static_cast<std::uint8_t>((0xFFu >> (kInBlock - hi)) & (0xFFu << lo));
}

/// Voxels lo..hi of `box` on one axis, as offsets in block b (an empty range when none).
std::array<std::int32_t, 2> in_block(std::int32_t lo, std::int32_t hi, std::int64_t b) {
  const std::int64_t first = b << kBlockShift;
  return {static_cast<std::int32_t>(std::max<std::int64_t>(lo, first) - first),
          static_cast<std::int32_t>(std::min<std::int64_t>(hi, first + kInBlock) - first)};
}

}  // namespace

VoxelMask::VoxelMask(std::span<const VoxelBox> boxes, std::uint64_t max_blocks) {
  std::array<std::int64_t, 3> lo, hi;
  lo.fill(std::numeric_limits<std::int64_t>::max());
  hi.fill(std::numeric_limits<std::int64_t>::min());
  for (const VoxelBox& b : boxes) {
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], block_of_voxel(b.lo[a]));
      hi[a] = std::max(hi[a], block_of_voxel(b.hi[a]));
    }
  }
  everything_ = false;
  if (boxes.empty()) return;  // no voxel: extent 0
  std::uint64_t cells = 1;
  for (int a = 0; a < 3; ++a) {
    origin_[a] = lo[a];
    extent_[a] = hi[a] - lo[a] + 1;
    cells *= static_cast<std::uint64_t>(extent_[a]);  // each at most 2^29: no overflow before the test
    if (cells > max_blocks) {
      everything_ = true;
      return;
    }
  }
  block_of_.assign(cells, kNoBlock);
  for (const VoxelBox& b : boxes) add(b);
}

std::size_t VoxelMask::cell(std::int64_t bx, std::int64_t by, std::int64_t bz) const {
  return static_cast<std::size_t>(((bz - origin_[2]) * extent_[1] + (by - origin_[1])) * extent_[0] + (bx - origin_[0]));
}

void VoxelMask::add(const VoxelBox& box) {
  for (std::int64_t bz = block_of_voxel(box.lo[2]); bz <= block_of_voxel(box.hi[2]); ++bz) {
    const auto [z0, z1] = in_block(box.lo[2], box.hi[2], bz);
    for (std::int64_t by = block_of_voxel(box.lo[1]); by <= block_of_voxel(box.hi[1]); ++by) {
      const auto [y0, y1] = in_block(box.lo[1], box.hi[1], by);
      for (std::int64_t bx = block_of_voxel(box.lo[0]); bx <= block_of_voxel(box.hi[0]); ++bx) {
        const auto [x0, x1] = in_block(box.lo[0], box.hi[0], bx);
        std::uint32_t& id = block_of_[cell(bx, by, bz)];
        if (id == kNoBlock) {
          id = static_cast<std::uint32_t>(rows_.size());
          rows_.emplace_back().fill(0);
        }
        Block& rows = rows_[id];
        const std::uint8_t bits = row_bits(x0, x1);
        for (std::int32_t z = z0; z <= z1; ++z) {
          for (std::int32_t y = y0; y <= y1; ++y) rows[y + 8 * z] |= bits;
        }
      }
    }
  }
}

bool VoxelMask::any_in(const VoxelBox& box) const {
  if (everything_) return true;
  std::array<std::int64_t, 3> first, last;
  for (int a = 0; a < 3; ++a) {
    first[a] = std::max(block_of_voxel(box.lo[a]), origin_[a]);
    last[a] = std::min(block_of_voxel(box.hi[a]), origin_[a] + extent_[a] - 1);
    if (first[a] > last[a]) return false;
  }
  for (std::int64_t bz = first[2]; bz <= last[2]; ++bz) {
    const auto [z0, z1] = in_block(box.lo[2], box.hi[2], bz);
    for (std::int64_t by = first[1]; by <= last[1]; ++by) {
      const auto [y0, y1] = in_block(box.lo[1], box.hi[1], by);
      for (std::int64_t bx = first[0]; bx <= last[0]; ++bx) {
        const std::uint32_t id = block_of_[cell(bx, by, bz)];
        if (id == kNoBlock) continue;
        const auto [x0, x1] = in_block(box.lo[0], box.hi[0], bx);
        const std::uint8_t bits = row_bits(x0, x1);
        const Block& rows = rows_[id];
        for (std::int32_t z = z0; z <= z1; ++z) {
          for (std::int32_t y = y0; y <= y1; ++y) {
            if ((rows[y + 8 * z] & bits) != 0) return true;
          }
        }
      }
    }
  }
  return false;
}

}  // namespace citymesh
