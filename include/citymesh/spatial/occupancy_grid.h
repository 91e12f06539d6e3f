// SPDX-License-Identifier: MIT
// Sparse boolean voxel grid in a local metric frame (OpenVDB behind this header): the coarse
// occupancy / empty-space pre-filter that spares exact triangle-tetrahedron tests.
#pragma once

#include <cstddef>
#include <memory>

#include "citymesh/core/vec.h"
#include "citymesh/spatial/voxel_box.h"

namespace citymesh {

class OccupancyGrid {
 public:
  /// `voxel_size` in metres, > 0. Voxel (i, j, k) covers [i, i+1) * voxel_size on each axis.
  explicit OccupancyGrid(double voxel_size);
  ~OccupancyGrid();
  OccupancyGrid(OccupancyGrid&&) noexcept;
  OccupancyGrid& operator=(OccupancyGrid&&) noexcept;

  [[nodiscard]] double voxel_size() const;
  /// 1 / voxel_size(): what voxel_box takes to give this grid's voxels.
  [[nodiscard]] double inverse_voxel_size() const { return inverse_of(voxel_size()); }
  /// What inverse_voxel_size() is for a grid of voxels of `voxel_size` metres.
  [[nodiscard]] static double inverse_of(double voxel_size) { return 1.0 / voxel_size; }
  /// Marks the voxel containing `p`.
  void mark_point(const Vec3f& p);
  /// Marks every voxel that overlaps the closed box [lo, hi].
  void mark_box(const Vec3f& lo, const Vec3f& hi);
  /// Marks voxels.lo..voxels.hi (see voxel_box, with 1 / voxel_size()).
  void mark_voxels(const VoxelBox& voxels);
  [[nodiscard]] bool occupied(const Vec3f& p) const;
  /// True when any voxel overlapping the closed box [lo, hi] is marked.
  [[nodiscard]] bool any_in_box(const Vec3f& lo, const Vec3f& hi) const;
  [[nodiscard]] std::size_t marked_voxels() const;

  /// Box queries for one thread, through a cache of the tree nodes last visited: consecutive
  /// boxes of a scan fall in the same nodes (answers as any_in_box; a grid's reader must not
  /// outlive it nor see it change).
  class Reader {
   public:
    explicit Reader(const OccupancyGrid& grid);
    ~Reader();
    Reader(const Reader&) = delete;
    Reader& operator=(const Reader&) = delete;
    /// True when any voxel overlapping the closed box [lo, hi] is marked.
    [[nodiscard]] bool any_in_box(const Vec3f& lo, const Vec3f& hi);

   private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
  };
  /// Marks every voxel marked in `other` (same voxel size), which is left empty.
  void merge(OccupancyGrid&& other);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace citymesh
