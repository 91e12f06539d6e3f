// SPDX-License-Identifier: MIT
#include <algorithm>
#include <array>
#include <cmath>
#include <iterator>
#include <numbers>

#include "citymesh/core/parallel.h"
#include "citymesh/core/radix_sort.h"
#include "frames.h"

namespace citymesh::change_detail {

namespace {

/// T (centroid c) overlaps U: c lies within `threshold` of U's plane and its projection on
/// that plane falls inside U (edges included), i.e. the point-to-triangle distance is at most
/// the threshold and is reached inside U.
[[gnu::always_inline]] inline bool overlaps(const Vec3d& c, const TriangleFrames& f, std::uint32_t u,
                                            double threshold) {
  const std::array<Vec3f, 3>& qf = f.corner[u];
  const TriangleCorners q{Vec3d(qf[0]), Vec3d(qf[1]), Vec3d(qf[2])};
  const Vec3d n(f.normal[u]);
  const double h = dot(c - q[0], n);
  if (std::abs(h) > threshold) return false;
  const Vec3d p = c - n * h;
  // Inside when p is on the inner side of every edge, measured about the corners' own winding
  // (the stored normal was turned towards the viewpoint, so its sign says nothing of it).
  const Vec3d winding = cross(q[1] - q[0], q[2] - q[0]);
  for (int k = 0; k < 3; ++k) {
    if (dot(cross(q[(k + 1) % 3] - q[k], p - q[k]), winding) < 0) return false;
  }
  return true;
}

/// Every point within `threshold` of U's plane whose projection falls inside U lies in this
/// box: U's box widened along each axis by the threshold times the normal's component (the
/// prism's box), padded so that float rounding never loses a point on its border.
Box3f prism_box(const TriangleFrames& f, std::size_t u, double threshold) {
  const Box3f box = f.bounds(u);
  const Vec3d n(f.normal[u]);
  const Vec3d widen{threshold * std::abs(n.x) + 1e-5, threshold * std::abs(n.y) + 1e-5,
                    threshold * std::abs(n.z) + 1e-5};
  return {Vec3f(Vec3d(box.min) - widen), Vec3f(Vec3d(box.max) + widen)};
}

/// Whether triangles t and u share a corner: the same vertex gives the same float corner, so
/// comparing positions finds mesh neighbours without the meshes' vertex ids.
bool share_a_corner(const TriangleFrames& f, std::uint32_t t, std::uint32_t u) {
  for (const Vec3f& a : f.corner[t]) {
    for (const Vec3f& b : f.corner[u]) {
      if (a == b) return true;
    }
  }
  return false;
}

/// The pairs (min, max) found from triangle g's side: every U whose prism holds g's centroid
/// (`hits`), with compatible normals, that g overlaps. Into `out.consistent` when U is of
/// another acquisition; into `out.layers` when it is of g's own and shares no corner with it
/// (two layers of one pass). A pair that U also finds from its side (U overlaps g, and U
/// asks) is kept by the smaller index only, so that each pair is listed once.
void pairs_of(const TriangleFrames& f, std::size_t g, std::span<const std::uint32_t> hits, double threshold,
              float cos_min, OverlappingPairs& out) {
  const std::uint32_t acq = f.index.acquisition_of(g);
  const std::size_t own_begin = f.index.offsets[acq], own_end = f.index.offsets[acq + 1];
  const auto t = static_cast<std::uint32_t>(g);
  for (const std::uint32_t u : hits) {
    const bool same_acquisition = u >= own_begin && u < own_end;
    if (u == t || dot(f.normal[g], f.normal[u]) < cos_min) continue;
    // Most hits of g's own pass are its neighbours on one sheet: told apart before the
    // overlap tests, which they would mostly fail anyway.
    if (same_acquisition && share_a_corner(f, t, u)) continue;
    if (!overlaps(Vec3d(f.centroid[g]), f, u, threshold)) continue;
    if (t > u && f.asks(u) && overlaps(Vec3d(f.centroid[u]), f, t, threshold)) continue;  // u lists it
    (same_acquisition ? out.layers : out.consistent).emplace_back(std::min(t, u), std::max(t, u));
  }
}

/// One block's pairs after another (emptying them as it goes), sorted.
std::vector<TrianglePair> concatenate_sorted(std::vector<OverlappingPairs>& blocks,
                                             std::vector<TrianglePair> OverlappingPairs::*list) {
  std::size_t total = 0;
  for (const OverlappingPairs& b : blocks) total += (b.*list).size();
  std::vector<TrianglePair> pairs;
  pairs.reserve(total);
  for (OverlappingPairs& b : blocks) {
    pairs.insert(pairs.end(), (b.*list).begin(), (b.*list).end());
    std::vector<TrianglePair>().swap(b.*list);
  }
  radix_sort_pairs(pairs);
  return pairs;
}

}  // namespace

OverlappingPairs find_overlapping_pairs(const TriangleFrames& f, const ChangeParams& params, ChangeStats& stats) {
  const double threshold = params.distance_threshold;
  const auto cos_min = static_cast<float>(std::cos(params.normal_angle * std::numbers::pi / 180.0) - 1e-6);
  std::vector<Box3f> boxes(f.size());
  parallel_for_blocks(f.size(), 16384, [&](std::size_t b, std::size_t e) {
    for (std::size_t g = b; g < e; ++g) boxes[g] = prism_box(f, g, threshold);
  });
  const BoxTree prisms(std::move(boxes));

  constexpr std::size_t kGrain = 4096;  // a multiple of the packet: packets stay in a block
  std::vector<OverlappingPairs> per_block((f.size() + kGrain - 1) / kGrain);
  parallel_for_blocks(f.size(), kGrain, [&](std::size_t begin, std::size_t end) {
    // In the tree's order, a triangle's candidates are near the previous one's: warm caches,
    // and packets of neighbouring centroids that share one walk down the tree.
    std::span<const std::uint32_t> order = prisms.storage_order().subspan(begin, end - begin);
    std::vector<std::uint32_t> asking;  // only triangles whose labels are wanted query
    if (!f.use.empty()) {
      std::copy_if(order.begin(), order.end(), std::back_inserter(asking), [&](std::uint32_t g) { return f.asks(g); });
      order = asking;
    }
    prisms.containing_in_packets(
        order.size(), [&](std::size_t i) { return f.centroid[order[i]]; },
        [&](std::size_t i, std::span<const std::uint32_t> hits) {
          pairs_of(f, order[i], hits, threshold, cos_min, per_block[begin / kGrain]);
        });
  });
  OverlappingPairs pairs;
  pairs.consistent = concatenate_sorted(per_block, &OverlappingPairs::consistent);
  pairs.layers = concatenate_sorted(per_block, &OverlappingPairs::layers);
  stats.consistent_pairs = pairs.consistent.size();
  return pairs;
}

}  // namespace citymesh::change_detail
