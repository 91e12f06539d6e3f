// SPDX-License-Identifier: MIT
// The paper's baseline mosaic: add acquisitions in date order, keep what is new.
#include <algorithm>
#include <numeric>

#include "citymesh/core/parallel.h"
#include "citymesh/core/stopwatch.h"
#include "citymesh/mosaic/merged_mesh.h"
#include "citymesh/mosaic/mosaic.h"
#include "citymesh/mosaic/proximity.h"
#include "internal.h"

namespace citymesh {

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

  const double reach = input.distance_threshold;
  for (const std::size_t a : order) {
    // What the earlier acquisitions kept, as one mesh (nothing of this one is selected yet).
    const MergedMesh kept = merge_selection(input.meshes, index, out.selected);
    const MeshProximity near(kept.mesh, reach);
    const Mesh& mesh = input.meshes[a];
    const std::size_t base = index.offsets[a];
    parallel_for_blocks(mesh.triangle_count(), 4096, [&](std::size_t begin, std::size_t end) {
      for (std::size_t t = begin; t < end; ++t) {
        if (change.kept[base + t] == 0) continue;
        const auto [p, q, r] = mesh.corners(t);
        out.selected[base + t] = near.any_within((p + q + r) / 3.0, reach) ? 0 : 1;
      }
    });
  }
  out.stats.candidates = static_cast<std::uint64_t>(std::count(change.kept.begin(), change.kept.end(), 1));
  out.stats.selected = static_cast<std::uint64_t>(std::count(out.selected.begin(), out.selected.end(), 1));
  out.stats.seconds_solve = clock.seconds();
  return out;
}

}  // namespace citymesh
