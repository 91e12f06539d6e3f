// SPDX-License-Identifier: MIT
// The paper's baseline mosaic (add acquisitions in date order, keep what is new) and the hole
// fill after the energy mosaic (the same rule, newest first, from the mosaic's selection).
#include <algorithm>
#include <atomic>

#include "citymesh/core/error.h"
#include "citymesh/core/geometry.h"
#include "citymesh/core/parallel.h"
#include "citymesh/core/stopwatch.h"
#include "citymesh/mosaic/merged_mesh.h"
#include "citymesh/mosaic/mosaic.h"
#include "citymesh/mosaic/proximity.h"
#include "internal.h"
#include "seen_through.h"

namespace citymesh {

namespace {

/// Per global triangle: 1 when it is a candidate (kept, not selected) with a selected
/// consistent partner clearly within `reach` of its centroid. Most candidates the energy
/// left out overlap a selected triangle: their pairs answer for them, and only the others
/// need the search (which took most of the hole fill's time). "Clearly": 0.1 mm inside, far
/// more than the merged mesh's coordinates differ from the meshes' own, so the search would
/// have found that partner too.
std::vector<std::uint8_t> covered_by_partners(const MosaicInput& input, const std::vector<std::uint8_t>& selected,
                                              double reach) {
  const ChangeResult& change = *input.change;
  const GlobalTriangles& index = change.index;
  std::vector<std::uint8_t> covered(index.size(), 0);
  constexpr double kClear = 1e-4;
  if (!(reach > kClear)) return covered;
  const double clear_sq = (reach - kClear) * (reach - kClear);
  const auto corners = [&](std::uint32_t g) {
    const std::uint32_t a = index.acquisition_of(g);
    return input.meshes[a].corners(g - index.offsets[a]);
  };
  const PackedPairs& pairs = change.consistent_pairs;
  parallel_for_blocks(pairs.block_count(), 4, [&](std::size_t begin, std::size_t end) {
    for (auto k = pairs.block_begin(begin), stop = pairs.block_begin(end); k != stop; ++k) {
      for (const auto& [candidate, partner] : {*k, TrianglePair{k->second, k->first}}) {
        if (change.kept[candidate] == 0 || selected[candidate] != 0 || selected[partner] == 0) continue;
        // Flags are only raised: any order of raising gives the same result.
        std::atomic_ref<std::uint8_t> flag(covered[candidate]);
        if (flag.load(std::memory_order_relaxed) != 0) continue;
        const auto [p, q, r] = corners(candidate);
        if (point_triangle_distance_sq((p + q + r) / 3.0, corners(partner)) <= clear_sq) {
          flag.store(1, std::memory_order_relaxed);
        }
      }
    }
  });
  return covered;
}

/// Per global triangle: 1 when the change step kept it, it is not selected and no selected
/// triangle lies within the distance threshold of its centroid.
std::vector<std::uint8_t> uncovered_by_selection(const MosaicInput& input, const std::vector<std::uint8_t>& selected) {
  const ChangeResult& change = *input.change;
  const GlobalTriangles& index = change.index;
  const double reach = input.distance_threshold;
  const std::vector<std::uint8_t> by_partner = covered_by_partners(input, selected, reach);
  const MergedMesh initial = merge_selection(input.meshes, index, selected);
  const MeshProximity near_initial(initial.mesh, reach);
  std::vector<std::uint8_t> open(index.size(), 0);
  for (std::size_t a = 0; a < input.meshes.size(); ++a) {
    const Mesh& mesh = input.meshes[a];
    const std::size_t base = index.offsets[a];
    parallel_for_blocks(mesh.triangle_count(), 4096, [&](std::size_t begin, std::size_t end) {
      // The block's candidates in mesh order (neighbours in a scan): asked in packets.
      std::vector<std::uint32_t> asked;
      std::vector<Vec3d> centroids;
      for (std::size_t t = begin; t < end; ++t) {
        if (change.kept[base + t] == 0 || selected[base + t] != 0 || by_partner[base + t] != 0) continue;
        const auto [p, q, r] = mesh.corners(t);
        asked.push_back(static_cast<std::uint32_t>(t));
        centroids.push_back((p + q + r) / 3.0);
      }
      std::vector<std::uint8_t> covered(asked.size());
      near_initial.any_within_each(centroids, reach, covered);
      for (std::size_t i = 0; i < asked.size(); ++i) open[base + asked[i]] = covered[i] != 0 ? 0 : 1;
    });
  }
  return open;
}

/// Clears open[g] where another pass saw through triangle g (`known`, per global triangle,
/// when given; else asked now), noting it (kNoteFillLeftOut) when `notes`; returns how many.
std::uint64_t drop_seen_through(const MosaicInput& input, const mosaic_detail::SeenThroughParams& params,
                                std::span<const std::uint8_t> known, std::vector<std::uint8_t>& open,
                                std::vector<std::uint8_t>* notes) {
  std::vector<std::uint32_t> ids;
  for (std::size_t g = 0; g < open.size(); ++g) {
    if (open[g] != 0) ids.push_back(static_cast<std::uint32_t>(g));
  }
  std::vector<std::uint8_t> seen(ids.size());
  if (known.empty()) {
    seen = mosaic_detail::seen_through(input.meshes, input.change->index, ids, params);
  } else {
    for (std::size_t i = 0; i < ids.size(); ++i) seen[i] = known[ids[i]];
  }
  std::uint64_t dropped = 0;
  for (std::size_t i = 0; i < ids.size(); ++i) {
    if (seen[i] != 0) {
      open[ids[i]] = 0;
      if (notes != nullptr) (*notes)[ids[i]] |= kNoteFillLeftOut;
      ++dropped;
    }
  }
  return dropped;
}

/// Visits the acquisitions in `order`; in each, selects the kept triangles with no selected
/// triangle within the distance threshold of their centroid (what is selected at the start of
/// the acquisition: its own triangles do not hide each other, but of two layers of one pass
/// only one is taken: keep_one_layer), unless, with `visibility`,
/// another pass saw through them. The triangles selected at the start are indexed once; the
/// ones added on the way are indexed again per acquisition (few, for the hole fill).
HoleFillCounts add_uncovered(const MosaicInput& input, std::span<const std::size_t> order,
                             std::vector<std::uint8_t>& selected, const mosaic_detail::SeenThroughParams* visibility,
                             std::span<const std::uint8_t> seen = {}, std::vector<std::uint8_t>* notes = nullptr) {
  const GlobalTriangles& index = input.change->index;
  const double reach = input.distance_threshold;
  std::vector<std::uint8_t> open = uncovered_by_selection(input, selected);
  HoleFillCounts counts;
  // Seen through or not does not depend on the selection: asked once, for every candidate.
  if (visibility != nullptr) counts.seen_through = drop_seen_through(input, *visibility, seen, open, notes);
  std::vector<std::uint8_t> added_so_far(selected.size(), 0);
  for (const std::size_t a : order) {
    const std::size_t base = index.offsets[a];
    const std::span<const std::uint8_t> open_here(open.data() + base, index.offsets[a + 1] - base);
    if (std::none_of(open_here.begin(), open_here.end(), [](std::uint8_t o) { return o != 0; })) continue;
    const MergedMesh later = merge_selection(input.meshes, index, added_so_far);
    const MeshProximity near_later(later.mesh, reach);
    const Mesh& mesh = input.meshes[a];
    std::vector<std::uint8_t> add(mesh.triangle_count(), 0);
    parallel_for_blocks(mesh.triangle_count(), 4096, [&](std::size_t begin, std::size_t stop) {
      for (std::size_t t = begin; t < stop; ++t) {
        if (open[base + t] == 0) continue;
        const auto [p, q, r] = mesh.corners(t);
        add[t] = near_later.any_within((p + q + r) / 3.0, reach) ? 0 : 1;
      }
    });
    (void)keep_one_layer(input, base, add);
    for (std::size_t t = 0; t < add.size(); ++t) {
      selected[base + t] |= add[t];
      added_so_far[base + t] |= add[t];
      counts.added += add[t];
      if (notes != nullptr && add[t] != 0) (*notes)[base + t] |= kNoteFilled;
    }
  }
  return counts;
}

}  // namespace

MosaicSelection select_update_model(const MosaicInput& input) {
  mosaic_detail::check_mosaic_input(input);
  Stopwatch clock;
  const ChangeResult& change = *input.change;
  MosaicSelection out;
  out.selected.assign(change.index.size(), 0);
  (void)add_uncovered(input, mosaic_detail::date_order(input), out.selected, nullptr);
  out.stats.candidates = static_cast<std::uint64_t>(std::count(change.kept.begin(), change.kept.end(), 1));
  out.stats.selected = static_cast<std::uint64_t>(std::count(out.selected.begin(), out.selected.end(), 1));
  out.stats.seconds_solve = clock.seconds();
  return out;
}

namespace {

/// Whether the centroid of global triangle g lies on global triangle u (lies_over).
bool centroid_on(const MosaicInput& input, std::uint32_t g, std::uint32_t u, double reach) {
  const GlobalTriangles& index = input.change->index;
  const auto corners = [&](std::uint32_t t) {
    const std::uint32_t a = index.acquisition_of(t);
    return input.meshes[a].corners(t - index.offsets[a]);
  };
  const auto [p, q, r] = corners(g);
  return mosaic_detail::lies_over((p + q + r) / 3.0, corners(u), reach);
}

}  // namespace

std::uint64_t keep_one_layer(const MosaicInput& input, std::size_t base, std::span<std::uint8_t> selected) {
  const PackedPairs& layers = input.change->layer_pairs;
  const auto is_forced = [&](std::size_t g) { return !input.forced.empty() && input.forced[g] != 0; };
  std::uint64_t dropped = 0;
  for (auto it = layers.lower_bound(static_cast<std::uint32_t>(base));
       it != layers.end() && it->first < base + selected.size(); ++it) {
    const auto [g, u] = *it;
    if (selected[g - base] == 0 || selected[u - base] == 0) continue;
    // The later one goes (in a pass's file order, a later turn), so that the earlier layer
    // stays whole where it is; a decision taken elsewhere (forced) stays. Only a triangle
    // whose centre the other covers goes: one that merely reaches over the other's edge
    // covers more beyond it, and dropping it would open a slit there.
    const auto [drop, stays] = is_forced(u) ? std::pair{g, u} : std::pair{u, g};
    if (is_forced(drop) || !centroid_on(input, drop, stays, input.distance_threshold)) continue;
    selected[drop - base] = 0;
    ++dropped;
  }
  return dropped;
}

HoleFillCounts fill_holes(const MosaicInput& input, std::vector<std::uint8_t>& selected,
                          std::span<const std::uint8_t> seen_through, std::vector<std::uint8_t>* notes) {
  mosaic_detail::check_mosaic_input(input);
  std::vector<std::size_t> order = mosaic_detail::date_order(input);
  std::reverse(order.begin(), order.end());
  // What another pass saw through is not put back: mostly facets one pass strung across a
  // window recess that another pass saw into (they lie on no surface), which the fill would
  // otherwise add as a second sheet standing in front of the selection.
  const mosaic_detail::SeenThroughParams visibility = mosaic_detail::mosaic_visibility(input.distance_threshold);
  if (!seen_through.empty() && seen_through.size() != input.change->index.size()) {
    throw ProcessingError("fill_holes: the seen-through flags do not cover every triangle");
  }
  if (notes != nullptr && notes->size() != input.change->index.size()) {
    throw ProcessingError("fill_holes: the notes do not cover every triangle");
  }
  return add_uncovered(input, order, selected, &visibility, seen_through, notes);
}

}  // namespace citymesh
