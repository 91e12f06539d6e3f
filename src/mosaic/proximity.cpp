// SPDX-License-Identifier: MIT
#include "citymesh/mosaic/proximity.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "citymesh/core/geometry.h"
#include "citymesh/core/parallel.h"
#include "citymesh/spatial/box_tree.h"
#include "internal.h"

namespace citymesh {

MeshProximity::MeshProximity(const Mesh& mesh, double max_reach) : mesh_(mesh) {
  std::vector<Box3f> boxes(mesh.triangle_count());
  parallel_for_blocks(boxes.size(), 16384, [&](std::size_t begin, std::size_t end) {
    for (std::size_t t = begin; t < end; ++t) {
      Box3d b;
      for (const Vec3d& p : mesh.corners(t)) b.extend(p);
      b = b.grown(max_reach + 1e-5);
      boxes[t] = {Vec3f(b.min), Vec3f(b.max)};
    }
  });
  tree_ = std::make_unique<BoxTree>(std::move(boxes));
}

MeshProximity::~MeshProximity() = default;

bool MeshProximity::any_within(const Vec3d& p, double reach, const std::function<bool(std::uint32_t)>& accept) const {
  thread_local std::vector<std::uint32_t> hits;
  tree_->containing(Vec3f(p), hits);
  const double reach_sq = reach * reach;
  return std::any_of(hits.begin(), hits.end(), [&](std::uint32_t t) {
    return (!accept || accept(t)) && point_triangle_distance_sq(p, mesh_.corners(t)) <= reach_sq;
  });
}

void MeshProximity::any_within_each(std::span<const Vec3d> points, double reach, std::span<std::uint8_t> within) const {
  const double reach_sq = reach * reach;
  tree_->containing_in_packets(
      points.size(), [&](std::size_t i) { return Vec3f(points[i]); },
      [&](std::size_t i, std::span<const std::uint32_t> hits) {
        within[i] = std::any_of(hits.begin(), hits.end(), [&](std::uint32_t t) {
          return point_triangle_distance_sq(points[i], mesh_.corners(t)) <= reach_sq;
        }) ? 1 : 0;
      });
}

}  // namespace citymesh

namespace citymesh {

bool mosaic_detail::lies_over(const Vec3d& p, const TriangleCorners& q, double reach) {
  const Vec3d winding = cross(q[1] - q[0], q[2] - q[0]);
  const double len = norm(winding);
  if (!(len > 0)) return false;
  const Vec3d n = winding / len;
  const double h = dot(p - q[0], n);
  if (std::abs(h) > reach) return false;
  const Vec3d f = p - n * h;
  for (int k = 0; k < 3; ++k) {
    if (dot(cross(q[(k + 1) % 3] - q[k], f - q[k]), winding) < 0) return false;
  }
  return true;
}

bool MeshProximity::any_over(const Vec3d& p, double reach, const std::function<bool(std::uint32_t)>& accept) const {
  thread_local std::vector<std::uint32_t> hits;
  tree_->containing(Vec3f(p), hits);
  return std::any_of(hits.begin(), hits.end(), [&](std::uint32_t t) {
    return (!accept || accept(t)) && mosaic_detail::lies_over(p, mesh_.corners(t), reach);
  });
}

}  // namespace citymesh
