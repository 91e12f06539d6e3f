// SPDX-License-Identifier: MIT
// Static kd-tree over 3D points in a local frame (nanoflann behind this header). Stitching
// matches boundary vertices with it.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "citymesh/core/vec.h"

namespace citymesh {

class PointKdTree {
 public:
  /// Builds the tree over `points` (copied). Points must be finite.
  explicit PointKdTree(std::vector<Vec3f> points);
  ~PointKdTree();
  PointKdTree(const PointKdTree&) = delete;
  PointKdTree& operator=(const PointKdTree&) = delete;

  [[nodiscard]] std::size_t size() const;
  /// Indices of the points within `radius` (metres, inclusive) of `query`, in increasing index
  /// order so that results never depend on the tree's internal order; `sorted = false` skips
  /// the sort for callers that only use the set.
  void radius_search(const Vec3f& query, float radius, std::vector<std::uint32_t>& out, bool sorted = true) const;
  /// The `k` nearest points, nearest first; equal distances by increasing index.
  [[nodiscard]] std::vector<std::uint32_t> nearest(const Vec3f& query, std::size_t k) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace citymesh
