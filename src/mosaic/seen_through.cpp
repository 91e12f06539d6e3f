// SPDX-License-Identifier: MIT
#include "seen_through.h"

#include <algorithm>
#include <atomic>
#include <cmath>

#include "citymesh/core/geometry.h"
#include "citymesh/core/parallel.h"
#include "citymesh/spatial/box_tree.h"

namespace citymesh::mosaic_detail {

namespace {

/// p inside the tetrahedron (viewpoint v, triangle q), between margin and depth from q's plane:
/// the change step's margin-reduced empty space, cut at the depth. For a point the ray through
/// it answers directly; the triangle-tetrahedron test's separating axes are not needed.
bool in_empty_space(const Vec3d& p, const Vec3d& v, const TriangleCorners& q, const SeenThroughParams& params) {
  const Vec3d winding = cross(q[1] - q[0], q[2] - q[0]);
  const double len = norm(winding);
  if (!(len > 0)) return false;
  const Vec3d n = winding / len;
  const double hv = dot(v - q[0], n), hp = dot(p - q[0], n);
  // Same side as the viewpoint, between the margin and the depth, and short of the viewpoint.
  if (hv * hp <= 0 || std::abs(hp) <= params.margin || std::abs(hp) > params.depth || std::abs(hp) >= std::abs(hv)) {
    return false;
  }
  // The ray from the viewpoint through p meets q's plane inside q.
  const Vec3d hit = v + (p - v) * (hv / (hv - hp));
  for (int k = 0; k < 3; ++k) {
    if (dot(cross(q[(k + 1) % 3] - q[k], hit - q[k]), winding) < 0) return false;
  }
  return true;
}

/// The box around the part of the tetrahedron (viewpoint v, triangle q) between `margin` and
/// `depth` from q's plane: the hull of its sections at those two distances, a thin slab in
/// front of q. Not q grown by the depth in every direction: that box also holds every point
/// on the surface itself and its neighbours, ten times the candidates on a street, and misses
/// grazing rays. Grown by a millimetre against rounding; inverted (meets nothing) when v is
/// no further from q's plane than the margin.
Box3f empty_space_box(const Vec3d& v, const TriangleCorners& q, const SeenThroughParams& params) {
  const Vec3d winding = cross(q[1] - q[0], q[2] - q[0]);
  const double len = norm(winding);
  const double hv = len > 0 ? std::abs(dot(v - q[0], winding / len)) : 0.0;
  if (!(hv > params.margin)) return {{1, 1, 1}, {-1, -1, -1}};
  const double near = params.margin / hv, far = std::min(1.0, params.depth / hv);
  Vec3d lo = q[0] + (v - q[0]) * near, hi = lo;
  for (const Vec3d& c : q) {
    for (const Vec3d& x : {c + (v - c) * near, c + (v - c) * far}) {
      lo = {std::min(lo.x, x.x), std::min(lo.y, x.y), std::min(lo.z, x.z)};
      hi = {std::max(hi.x, x.x), std::max(hi.y, x.y), std::max(hi.z, x.z)};
    }
  }
  constexpr double kPad = 1e-3;
  return {Vec3f(lo - Vec3d{kPad, kPad, kPad}), Vec3f(hi + Vec3d{kPad, kPad, kPad})};
}

}  // namespace

std::vector<std::uint8_t> seen_through(std::span<const Mesh> meshes, const GlobalTriangles& index,
                                       std::span<const std::uint32_t> triangles, const SeenThroughParams& params) {
  std::vector<std::uint8_t> seen(triangles.size(), 0);
  if (triangles.empty()) return seen;
  std::vector<Vec3d> centroid(triangles.size());
  std::vector<std::uint32_t> mesh_of(triangles.size());
  std::vector<Box3f> points(triangles.size());
  for (std::size_t i = 0; i < triangles.size(); ++i) {
    mesh_of[i] = index.acquisition_of(triangles[i]);
    const auto [p, q, r] = meshes[mesh_of[i]].corners(triangles[i] - index.offsets[mesh_of[i]]);
    centroid[i] = (p + q + r) / 3.0;
    points[i] = {Vec3f(centroid[i]), Vec3f(centroid[i])};
  }
  const BoxTree tree(std::move(points));
  for (std::size_t b = 0; b < meshes.size(); ++b) {
    const Mesh& other = meshes[b];
    if (!other.has_sensor_positions()) continue;
    parallel_for_blocks(other.triangle_count(), 8192, [&](std::size_t begin, std::size_t end) {
      std::vector<std::uint32_t> hits;
      for (std::size_t t = begin; t < end; ++t) {
        const TriangleCorners q = other.corners(t);
        const Vec3d v = other.viewpoint(t);
        tree.overlapping(empty_space_box(v, q, params), hits);
        if (hits.empty()) continue;
        for (const std::uint32_t i : hits) {
          // Flags are only raised: any order of raising gives the same result.
          if (mesh_of[i] != b && in_empty_space(centroid[i], v, q, params)) {
            std::atomic_ref<std::uint8_t>(seen[i]).store(1, std::memory_order_relaxed);
          }
        }
      }
    });
  }
  return seen;
}

}  // namespace citymesh::mosaic_detail
