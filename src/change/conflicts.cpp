// SPDX-License-Identifier: MIT
#include <algorithm>
#include <atomic>
#include <cmath>

#include "citymesh/core/parallel.h"
#include "frames.h"

namespace citymesh::change_detail {

namespace {

Vec3f lerp(const Vec3f& a, const Vec3f& b, float t) { return a + (b - a) * t; }

/// Marks every voxel the empty space of triangle g crosses: the tetrahedron is cut into slabs
/// about one voxel long from the viewpoint, and each slab's box (the hull of its two end
/// cross-sections contains the slab) is marked.
void mark_empty_space(const TriangleFrames& f, std::size_t g, OccupancyGrid& grid) {
  const TetrahedronCorners q = f.empty_space(g);
  const Vec3f v(q[0]), a(q[1]), b(q[2]), c(q[3]);
  const double length = std::max({norm(q[1] - q[0]), norm(q[2] - q[0]), norm(q[3] - q[0])});
  const auto steps = static_cast<int>(std::clamp(std::ceil(length / grid.voxel_size()), 1.0, 100000.0));
  const auto corner_box = [&](float t0, float t1, Vec3f& lo, Vec3f& hi) {
    const Vec3f pts[6] = {lerp(v, a, t0), lerp(v, b, t0), lerp(v, c, t0),
                          lerp(v, a, t1), lerp(v, b, t1), lerp(v, c, t1)};
    lo = hi = pts[0];
    for (const Vec3f& p : pts) {
      lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
      hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
    }
  };
  for (int k = 0; k < steps; ++k) {
    Vec3f lo, hi;
    corner_box(static_cast<float>(k) / static_cast<float>(steps), static_cast<float>(k + 1) / static_cast<float>(steps),
               lo, hi);
    grid.mark_box(lo, hi);
  }
}

}  // namespace

std::vector<OccupancyGrid> build_empty_space_grids(const TriangleFrames& f, const ChangeParams& params,
                                                   ChangeStats& stats) {
  const std::size_t n = f.acquisitions();
  std::vector<OccupancyGrid> grids;
  for (std::size_t a = 0; a < n; ++a) grids.emplace_back(params.voxel_size);
  parallel_for_blocks(n, 1, [&](std::size_t begin, std::size_t end) {
    for (std::size_t a = begin; a < end; ++a) {
      for (std::size_t g = f.index.offsets[a]; g < f.index.offsets[a + 1]; ++g) {
        if (f.empty_scale[g] > 0) mark_empty_space(f, g, grids[a]);
      }
    }
  });
  for (const OccupancyGrid& grid : grids) stats.marked_voxels += grid.marked_voxels();
  return grids;
}

namespace {

/// Triangles and their boxes, for the box collision.
struct BoxedTriangles {
  std::vector<std::uint32_t> ids;
  std::vector<Box3f> boxes;
};

/// The triangles that must be tested against acquisition j's empty space: older, not
/// consistent with j, and (with the pre-filter) near a voxel of j's grid.
BoxedTriangles conflict_candidates(const TriangleFrames& f, const PartnerBits& partners,
                                   std::span<const OccupancyGrid> grids, std::size_t j, const ChangeParams& params,
                                   ChangeStats& stats) {
  BoxedTriangles out;
  for (std::size_t a = 0; a < f.acquisitions(); ++a) {
    if (!(f.dates[a] < f.dates[j])) continue;
    for (std::size_t g = f.index.offsets[a]; g < f.index.offsets[a + 1]; ++g) {
      if (partners.has(g, j)) continue;
      ++stats.conflict_candidates;
      const Box3f box = f.bounds(g);
      if (params.prefilter && !grids[j].any_in_box(box.min, box.max)) {
        ++stats.prefilter_skipped;
        continue;
      }
      out.ids.push_back(static_cast<std::uint32_t>(g));
      out.boxes.push_back(box);
    }
  }
  return out;
}

}  // namespace

ConflictFlags find_conflicts(const TriangleFrames& f, const PartnerBits& partners, std::span<const OccupancyGrid> grids,
                             const ChangeParams& params, ChangeStats& stats) {
  ConflictFlags flags;
  flags.conflicting.assign(f.size(), 0);
  flags.refutes.assign(f.size(), 0);
  std::atomic<std::uint64_t> tests{0};
  for (std::size_t j = 0; j < f.acquisitions(); ++j) {
    const BoxedTriangles older = conflict_candidates(f, partners, grids, j, params, stats);
    if (older.ids.empty()) continue;
    std::vector<std::uint32_t> spaces;
    for (std::size_t g = f.index.offsets[j]; g < f.index.offsets[j + 1]; ++g) {
      if (f.empty_scale[g] > 0) spaces.push_back(static_cast<std::uint32_t>(g));
    }
    std::vector<Box3f> space_boxes(spaces.size());
    parallel_for_blocks(spaces.size(), 16384, [&](std::size_t b, std::size_t e) {
      for (std::size_t i = b; i < e; ++i) space_boxes[i] = f.empty_space_bounds(spaces[i]);
    });
    // Every overlapping pair is tested (no early exit) so that `refutes` does not depend on
    // the order Embree reports pairs in; the flags are only ever raised, so any order of
    // raising gives the same result.
    collide_boxes(older.boxes, space_boxes, [&](std::span<const BoxPair> batch) {
      for (const BoxPair& p : batch) {
        const std::uint32_t t = older.ids[p.a], u = spaces[p.b];
        if (triangle_intersects_tetrahedron(f.corners(t), f.empty_space(u))) {
          std::atomic_ref<std::uint8_t>(flags.conflicting[t]).store(1, std::memory_order_relaxed);
          std::atomic_ref<std::uint8_t>(flags.refutes[u]).store(1, std::memory_order_relaxed);
        }
      }
      tests.fetch_add(batch.size(), std::memory_order_relaxed);
    });
  }
  stats.exact_tests = tests.load();
  return flags;
}

}  // namespace citymesh::change_detail
