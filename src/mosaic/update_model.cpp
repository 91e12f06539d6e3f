// SPDX-License-Identifier: MIT
// The paper's baseline mosaic (add acquisitions in date order, keep what is new) and the hole
// fill after the energy mosaic (the same rule, newest first, from the mosaic's selection).
#include <algorithm>
#include <numeric>

#include "citymesh/core/parallel.h"
#include "citymesh/core/stopwatch.h"
#include "citymesh/mosaic/merged_mesh.h"
#include "citymesh/mosaic/mosaic.h"
#include "citymesh/mosaic/proximity.h"
#include "internal.h"

namespace citymesh {

namespace {

/// Visits the acquisitions in `order`; in each, selects the kept triangles with no selected
/// triangle within the distance threshold of their centroid (what is selected at the start of
/// the acquisition: its own triangles never hide each other). Returns how many were added.
/// The triangles selected at the start are indexed once; the ones added on the way are
/// indexed again per acquisition (few, for the hole fill).
std::uint64_t add_uncovered(const MosaicInput& input, std::span<const std::size_t> order, std::vector<std::uint8_t>& selected) {
  const ChangeResult& change = *input.change;
  const GlobalTriangles& index = change.index;
  const double reach = input.distance_threshold;
  const MergedMesh initial = merge_selection(input.meshes, index, selected);
  const MeshProximity near_initial(initial.mesh, reach);
  std::vector<std::uint8_t> added_so_far(selected.size(), 0);
  std::uint64_t added = 0;
  for (const std::size_t a : order) {
    const MergedMesh later = merge_selection(input.meshes, index, added_so_far);
    const MeshProximity near_later(later.mesh, reach);
    const Mesh& mesh = input.meshes[a];
    const std::size_t base = index.offsets[a];
    std::vector<std::uint8_t> add(mesh.triangle_count(), 0);
    parallel_for_blocks(mesh.triangle_count(), 4096, [&](std::size_t begin, std::size_t end) {
      for (std::size_t t = begin; t < end; ++t) {
        if (change.kept[base + t] == 0 || selected[base + t] != 0) continue;
        const auto [p, q, r] = mesh.corners(t);
        const Vec3d centroid = (p + q + r) / 3.0;
        add[t] = near_initial.any_within(centroid, reach) || near_later.any_within(centroid, reach) ? 0 : 1;
      }
    });
    for (std::size_t t = 0; t < add.size(); ++t) {
      selected[base + t] |= add[t];
      added_so_far[base + t] |= add[t];
      added += add[t];
    }
  }
  return added;
}

/// Acquisition indices by date (config order on equal dates).
std::vector<std::size_t> date_order(const MosaicInput& input) {
  std::vector<std::size_t> order(input.meshes.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return input.dates[a] < input.dates[b]; });
  return order;
}

}  // namespace

MosaicSelection select_update_model(const MosaicInput& input) {
  mosaic_detail::check_mosaic_input(input);
  Stopwatch clock;
  const ChangeResult& change = *input.change;
  MosaicSelection out;
  out.selected.assign(change.index.size(), 0);
  add_uncovered(input, date_order(input), out.selected);
  out.stats.candidates = static_cast<std::uint64_t>(std::count(change.kept.begin(), change.kept.end(), 1));
  out.stats.selected = static_cast<std::uint64_t>(std::count(out.selected.begin(), out.selected.end(), 1));
  out.stats.seconds_solve = clock.seconds();
  return out;
}

std::uint64_t fill_holes(const MosaicInput& input, std::vector<std::uint8_t>& selected) {
  mosaic_detail::check_mosaic_input(input);
  std::vector<std::size_t> order = date_order(input);
  std::reverse(order.begin(), order.end());
  return add_uncovered(input, order, selected);
}

}  // namespace citymesh
