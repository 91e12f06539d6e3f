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

/// The empty space between one triangle q of a pass and its viewpoint v (a tetrahedron), with
/// q's plane worked out once for every point asked about.
class EmptySpace {
 public:
  EmptySpace(const Vec3d& v, const TriangleCorners& q) : v_(v), q_(q), winding_(cross(q[1] - q[0], q[2] - q[0])) {
    const double len = norm(winding_);
    if (len > 0) {
      n_ = winding_ / len;
      hv_ = dot(v - q[0], n_);
    }
  }

  /// p inside the tetrahedron, between margin and depth from q's plane: the change step's
  /// margin-reduced empty space, cut at the depth. For a point the ray through it answers
  /// directly; the triangle-tetrahedron test's separating axes are not needed.
  [[nodiscard]] bool contains(const Vec3d& p, const SeenThroughParams& params) const {
    const double hp = dot(p - q_[0], n_);
    // Same side as the viewpoint, between the margin and the depth, and short of the viewpoint.
    if (hv_ * hp <= 0 || std::abs(hp) <= params.margin || std::abs(hp) > params.depth || std::abs(hp) >= std::abs(hv_)) {
      return false;
    }
    // The ray from the viewpoint through p meets q's plane inside q.
    const Vec3d hit = v_ + (p - v_) * (hv_ / (hv_ - hp));
    for (int k = 0; k < 3; ++k) {
      if (dot(cross(q_[(k + 1) % 3] - q_[k], hit - q_[k]), winding_) < 0) return false;
    }
    return true;
  }

  /// The box around the part between `margin` and `depth` from q's plane: the hull of its
  /// sections at those two distances, a thin slab in front of q. Not q grown by the depth in
  /// every direction: that box also holds every point on the surface itself and its
  /// neighbours, ten times the candidates on a street, and misses grazing rays. Grown by a
  /// millimetre, which covers the float rounding of the points looked up; empty when v is no
  /// further from q's plane than the margin.
  [[nodiscard]] Box3d box(const SeenThroughParams& params) const {
    Box3d b;
    const double hv = std::abs(hv_);
    if (!(hv > params.margin)) return b;
    const double near = params.margin / hv, far = std::min(1.0, params.depth / hv);
    for (const Vec3d& c : q_) {
      b.extend(c + (v_ - c) * near);
      b.extend(c + (v_ - c) * far);
    }
    constexpr double kPad = 1e-3;
    return b.grown(kPad);
  }

 private:
  Vec3d v_;
  TriangleCorners q_;
  Vec3d winding_, n_{};
  double hv_ = 0;  ///< the viewpoint's signed distance from q's plane; 0: degenerate q
};

/// Triangles of the other pass whose empty spaces share one tree query.
constexpr std::size_t kRun = 16;
/// Above this many points in a run's box, each triangle's box is asked on its own.
constexpr std::size_t kFewHits = 4 * kRun;

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
      std::vector<EmptySpace> spaces;
      std::vector<Box3d> boxes;
      // Consecutive triangles of a scan lie side by side: one tree query for a run of them,
      // then each one's own box among the few points found (a query per triangle was most of
      // the check's time: 1.4 points per slab on a street).
      for (std::size_t run = begin; run < end; run += kRun) {
        const std::size_t stop = std::min(end, run + kRun);
        spaces.clear();
        boxes.clear();
        Box3d all;
        for (std::size_t t = run; t < stop; ++t) {
          spaces.emplace_back(other.viewpoint(t), other.corners(t));
          boxes.push_back(spaces.back().box(params));
          all.extend(boxes.back());
        }
        if (all.empty()) continue;
        tree.overlapping({Vec3f(all.min), Vec3f(all.max)}, hits);
        // Whether point i (of another mesh than b) is flagged once empty space k is asked.
        // Flags are only raised: any order of raising gives the same result.
        const auto flagged_by = [&](std::uint32_t i, std::size_t k) {
          if (!boxes[k].contains(centroid[i])) return false;
          std::atomic_ref<std::uint8_t> flag(seen[i]);
          if (flag.load(std::memory_order_relaxed) != 0) return true;
          if (!spaces[k].contains(centroid[i], params)) return false;
          flag.store(1, std::memory_order_relaxed);
          return true;
        };
        if (hits.size() <= kFewHits) {
          for (const std::uint32_t i : hits) {
            if (mesh_of[i] == b) continue;
            for (std::size_t k = 0; k < spaces.size(); ++k) {
              if (flagged_by(i, k)) break;
            }
          }
          continue;
        }
        // Large empty spaces (a spinning scanner's far, grazing triangles: thousands of points
        // in a run's box): a query per triangle instead of every point against every box.
        for (std::size_t k = 0; k < spaces.size(); ++k) {
          if (boxes[k].empty()) continue;
          tree.overlapping({Vec3f(boxes[k].min), Vec3f(boxes[k].max)}, hits);
          for (const std::uint32_t i : hits) {
            if (mesh_of[i] != b) (void)flagged_by(i, k);
          }
        }
      }
    });
  }
  return seen;
}

}  // namespace citymesh::mosaic_detail
