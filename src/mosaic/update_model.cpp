// SPDX-License-Identifier: MIT
// The paper's baseline mosaic: add acquisitions in date order, keep what is new.
#include <algorithm>
#include <numeric>

#include "citymesh/core/geometry.h"
#include "citymesh/core/parallel.h"
#include "citymesh/core/stopwatch.h"
#include "citymesh/mosaic/mosaic.h"
#include "citymesh/spatial/box_tree.h"
#include "internal.h"

namespace citymesh {

namespace {

TriangleCorners corners_of(const Mesh& m, std::size_t t) {
  const Triangle& tri = m.triangles[t];
  return {Vec3d(m.positions[tri[0]]), Vec3d(m.positions[tri[1]]), Vec3d(m.positions[tri[2]])};
}

/// The box of the points within `reach` of the triangle.
Box3f reach_box(const TriangleCorners& c, double reach) {
  Vec3d lo = c[0], hi = c[0];
  for (const Vec3d& p : c) {
    lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
    hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
  }
  const Vec3d r{reach + 1e-5, reach + 1e-5, reach + 1e-5};
  return {Vec3f(lo - r), Vec3f(hi + r)};
}

}  // namespace

MosaicSelection select_update_model(const MosaicInput& input) {
  mosaic_detail::check_mosaic_input(input);
  Stopwatch clock;
  const ChangeResult& change = *input.change;
  const GlobalTriangles& index = change.index;
  MosaicSelection out;
  out.selected.assign(index.size(), 0);
  std::vector<std::size_t> order(input.meshes.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return input.dates[a] < input.dates[b]; });

  const double reach = input.distance_threshold, reach_sq = reach * reach;
  std::vector<std::uint32_t> kept_ids;  // global ids of the selected triangles so far
  std::vector<Box3f> kept_boxes;
  for (const std::size_t a : order) {
    const Mesh& mesh = input.meshes[a];
    const std::size_t base = index.offsets[a];
    const BoxTree tree(kept_boxes);  // the triangles of earlier acquisitions only
    parallel_for_blocks(mesh.triangle_count(), 4096, [&](std::size_t begin, std::size_t end) {
      std::vector<std::uint32_t> hits;
      for (std::size_t t = begin; t < end; ++t) {
        if (change.kept[base + t] == 0) continue;
        const TriangleCorners c = corners_of(mesh, t);
        const Vec3d centroid = (c[0] + c[1] + c[2]) / 3.0;
        tree.containing(Vec3f(centroid), hits);
        const bool covered = std::any_of(hits.begin(), hits.end(), [&](std::uint32_t h) {
          const std::uint32_t g = kept_ids[h], b = index.acquisition_of(g);
          return point_triangle_distance_sq(centroid, corners_of(input.meshes[b], g - index.offsets[b])) <= reach_sq;
        });
        out.selected[base + t] = covered ? 0 : 1;
      }
    });
    for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
      if (out.selected[base + t] == 0) continue;
      kept_ids.push_back(static_cast<std::uint32_t>(base + t));
      kept_boxes.push_back(reach_box(corners_of(mesh, t), reach));
    }
  }
  out.stats.candidates = static_cast<std::uint64_t>(std::count(change.kept.begin(), change.kept.end(), 1));
  out.stats.selected = kept_ids.size();
  out.stats.seconds_solve = clock.seconds();
  return out;
}

}  // namespace citymesh
