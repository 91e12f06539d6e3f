// SPDX-License-Identifier: MIT
// Sparse boolean voxel grid in a local metric frame (OpenVDB behind this header): the coarse
// occupancy / empty-space pre-filter that spares exact triangle-tetrahedron tests.
#pragma once

#include <cstddef>
#include <memory>

#include "citymesh/core/vec.h"

namespace citymesh {

class OccupancyGrid {
 public:
  /// `voxel_size` in metres, > 0. Voxel (i, j, k) covers [i, i+1) * voxel_size on each axis.
  explicit OccupancyGrid(double voxel_size);
  ~OccupancyGrid();
  OccupancyGrid(OccupancyGrid&&) noexcept;
  OccupancyGrid& operator=(OccupancyGrid&&) noexcept;

  [[nodiscard]] double voxel_size() const;
  /// Marks the voxel containing `p`.
  void mark_point(const Vec3f& p);
  /// Marks every voxel that overlaps the closed box [lo, hi].
  void mark_box(const Vec3f& lo, const Vec3f& hi);
  [[nodiscard]] bool occupied(const Vec3f& p) const;
  /// True when any voxel overlapping the closed box [lo, hi] is marked.
  [[nodiscard]] bool any_in_box(const Vec3f& lo, const Vec3f& hi) const;
  [[nodiscard]] std::size_t marked_voxels() const;
  /// Marks every voxel marked in `other` (same voxel size), which is left empty.
  void merge(OccupancyGrid&& other);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace citymesh
