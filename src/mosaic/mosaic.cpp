// SPDX-License-Identifier: MIT
#include "citymesh/mosaic/mosaic.h"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <numbers>
#include <numeric>

#include "citymesh/core/error.h"
#include "citymesh/core/parallel.h"
#include "citymesh/core/stopwatch.h"
#include "internal.h"
#include "mesh_edges.h"
#include "seen_through.h"

namespace citymesh {

using mosaic_detail::MeshEdges;

std::string_view quality_measure_name(QualityMeasure q) {
  switch (q) {
    case QualityMeasure::area:
      return "area";
    case QualityMeasure::resolution:
      return "resolution";
    default:
      return "constant";
  }
}

std::string_view mosaic_method_name(MosaicMethod m) {
  return m == MosaicMethod::update_model ? "update-model" : "energy";
}

void mosaic_detail::check_mosaic_input(const MosaicInput& input) {
  if (input.change == nullptr) throw ProcessingError("mosaic: no change detection result");
  std::size_t total = 0;
  for (const Mesh& m : input.meshes) total += m.triangle_count();
  if (total != input.change->index.size() || input.change->kept.size() != total) {
    throw ProcessingError("mosaic: the change detection result does not match the meshes");
  }
  if (input.dates.size() != input.meshes.size()) throw ProcessingError("mosaic: one date per mesh is needed");
  if (!input.forced.empty() && input.forced.size() != total) {
    throw ProcessingError("mosaic: the forced flags do not match the meshes");
  }
}

std::vector<std::size_t> mosaic_detail::date_order(const MosaicInput& input) {
  std::vector<std::size_t> order(input.meshes.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return input.dates[a] < input.dates[b]; });
  return order;
}

namespace {

struct TriangleShape {
  double area = 0, longest_edge = 0;
  Vec3f centroid;
  Vec3d winding;  ///< twice the area times the unit normal
};

/// Where a seam inside a mesh costs more: along a crease.
struct Crease {
  double cos_angle;  ///< the two triangles' normals are further apart than this cosine
  double weight;
};

/// The seam term's factor for the edge shared by two triangles of windings na and nb:
/// crease.weight along a crease, else 1. A seam at a corner leaves each pass's own chamfer to
/// meet the other's.
double seam_factor(const Vec3d& na, const Vec3d& nb, const Crease& crease) {
  const double scale = norm(na) * norm(nb);
  return scale > 0 && dot(na, nb) < crease.cos_angle * scale ? crease.weight : 1.0;
}

TriangleShape shape(const Mesh& m, std::size_t t) {
  const auto [a, b, c] = m.corners(t);
  const Vec3d winding = cross(b - a, c - a);
  return {0.5 * norm(winding), std::max({norm(b - a), norm(c - b), norm(a - c)}), Vec3f((a + b + c) / 3.0), winding};
}

/// Each variable's centroid along the longer horizontal extent of the scene: where the
/// group moves cut their slabs (a street is long and narrow).
std::vector<float> slab_coordinates(std::span<const TriangleShape> shapes) {
  float x_lo = FLT_MAX, x_hi = -FLT_MAX, y_lo = FLT_MAX, y_hi = -FLT_MAX;
  for (const TriangleShape& s : shapes) {
    x_lo = std::min(x_lo, s.centroid.x);
    x_hi = std::max(x_hi, s.centroid.x);
    y_lo = std::min(y_lo, s.centroid.y);
    y_hi = std::max(y_hi, s.centroid.y);
  }
  const bool along_x = x_hi - x_lo >= y_hi - y_lo;
  std::vector<float> out;
  out.reserve(shapes.size());
  for (const TriangleShape& s : shapes) out.push_back(along_x ? s.centroid.x : s.centroid.y);
  return out;
}

/// Makes x = 0 cost more, for every forced variable, than anything x = 1 can cost it: its
/// own unary terms plus every pair term it is part of.
void force_selected(std::span<const std::uint8_t> forced, MosaicEnergy& e) {
  std::vector<double> at_stake(e.triangle_of.size(), 0.0);
  for (const auto& p : e.energy.pairs) {
    const double worst = std::max({std::abs(p.e00), std::abs(p.e01), std::abs(p.e10), std::abs(p.e11)});
    at_stake[p.i] += worst;
    at_stake[p.j] += worst;
  }
  for (std::size_t v = 0; v < e.triangle_of.size(); ++v) {
    if (forced[e.triangle_of[v]] == 0) continue;
    e.energy.unary[v][0] = 1.0 + std::abs(e.energy.unary[v][1]) + 2.0 * at_stake[v];
  }
}

}  // namespace

MosaicEnergy build_mosaic_energy(const MosaicInput& input, const MosaicParams& params) {
  mosaic_detail::check_mosaic_input(input);
  const ChangeResult& change = *input.change;
  const GlobalTriangles& index = change.index;
  MosaicEnergy out;
  std::vector<std::uint32_t> variable_of(index.size(), UINT32_MAX);
  for (std::uint32_t g = 0; g < index.size(); ++g) {
    if (change.kept[g] == 0) continue;
    variable_of[g] = static_cast<std::uint32_t>(out.triangle_of.size());
    out.triangle_of.push_back(g);
  }
  const std::size_t n = out.triangle_of.size();
  out.stats.candidates = n;

  std::vector<MeshEdges> edges(input.meshes.size());
  parallel_for_blocks(input.meshes.size(), 1, [&](std::size_t begin, std::size_t end) {
    for (std::size_t a = begin; a < end; ++a) {
      const std::span<const std::uint8_t> kept(change.kept.data() + index.offsets[a], input.meshes[a].triangle_count());
      edges[a] = mosaic_detail::mesh_edges(input.meshes[a], kept);
    }
  });
  double length_sum = 0;
  std::uint64_t length_count = 0;
  for (const MeshEdges& e : edges) {
    length_sum += e.edge_length_sum;
    length_count += e.edge_count;
  }
  const double unit = length_count > 0 && length_sum > 0 ? length_sum / double(length_count) : 1.0;
  out.stats.length_unit = unit;

  std::vector<TriangleShape> shapes(n);
  parallel_for_blocks(n, 16384, [&](std::size_t begin, std::size_t end) {
    for (std::size_t v = begin; v < end; ++v) {
      const std::uint32_t g = out.triangle_of[v], a = index.acquisition_of(g);
      shapes[v] = shape(input.meshes[a], g - index.offsets[a]);
    }
  });
  double area_sum = 0;
  for (const TriangleShape& s : shapes) area_sum += s.area;
  out.coordinate = slab_coordinates(shapes);
  const double mean_area = n > 0 && area_sum > 0 ? area_sum / double(n) : 1.0;

  // Facets another pass saw through are worth less (seen_through_quality): the same check as
  // the hole fill's, asked of every candidate.
  if (params.seen_through_quality != 1.0) {
    out.seen_through = mosaic_detail::seen_through(input.meshes, index, out.triangle_of,
                                                   mosaic_detail::mosaic_visibility(input.distance_threshold));
  }
  out.stats.seen_through = static_cast<std::uint64_t>(std::count(out.seen_through.begin(), out.seen_through.end(), 1));

  out.energy.unary.resize(n);
  out.quality.resize(n);
  out.boundary.resize(n);
  parallel_for_blocks(n, 16384, [&](std::size_t begin, std::size_t end) {
    for (std::size_t v = begin; v < end; ++v) {
      const std::uint32_t g = out.triangle_of[v], a = index.acquisition_of(g);
      double q = 1.0;
      if (params.quality == QualityMeasure::area) q = shapes[v].area / mean_area;
      if (params.quality == QualityMeasure::resolution) {
        q = shapes[v].area / mean_area * unit / std::max(shapes[v].longest_edge, 1e-9);
      }
      if (!out.seen_through.empty() && out.seen_through[v] != 0) q *= params.seen_through_quality;
      out.quality[v] = -params.quality_weight * q;
      out.boundary[v] = params.boundary_weight * edges[a].boundary_length[g - index.offsets[a]] / unit;
      out.energy.unary[v] = {0.0, out.quality[v] + out.boundary[v]};
    }
  });
  std::size_t seam_count = 0;
  for (const MeshEdges& e : edges) seam_count += e.shared.size();
  // No regrowth copies: at most a row of values per seam term, one for the overlap terms.
  out.energy.pairs.reserve(seam_count + change.consistent_pairs.size(), seam_count + 1);
  const Crease crease{std::cos(params.crease_angle * std::numbers::pi / 180.0), params.crease_weight};
  for (std::size_t a = 0; a < edges.size(); ++a) {
    for (const auto& s : edges[a].shared) {
      const std::uint32_t va = variable_of[index.offsets[a] + s.a], vb = variable_of[index.offsets[a] + s.b];
      const double w =
          params.seam_weight * s.length / unit * seam_factor(shapes[va].winding, shapes[vb].winding, crease);
      out.energy.pairs.push_back({va, vb, 0, w, w, 0});
    }
  }
  out.stats.seam_terms = out.energy.pairs.size();
  for (const auto& [g, u] : change.consistent_pairs) {
    if (variable_of[g] == UINT32_MAX || variable_of[u] == UINT32_MAX) continue;
    out.energy.pairs.push_back({variable_of[g], variable_of[u], 0, 0, 0, params.overlap_weight});
  }
  out.stats.overlap_terms = out.energy.pairs.size() - out.stats.seam_terms;
  if (!input.forced.empty()) force_selected(input.forced, out);
  return out;
}

namespace {

/// Slabs of the group moves: two from 32 k variables on (below, a cut takes a few
/// milliseconds). More slabs cost more border work and, on the 300 k-variable bench street,
/// a worse energy (4 slabs: 0.15 % higher); a function of the problem only, so that the
/// selection is the same on any number of threads.
std::uint32_t slab_count(std::size_t variables) { return variables >= 32768 ? 2 : 1; }

/// The weighted terms of labelling x, for the report.
void account(const MosaicEnergy& e, std::span<const std::int8_t> x, MosaicStats& stats) {
  for (std::size_t v = 0; v < x.size(); ++v) {
    if (x[v] == 0) continue;
    stats.quality += e.quality[v];
    stats.boundary += e.boundary[v];
    ++stats.selected;
  }
  std::size_t k = 0;
  for (const EnergyPair p : e.energy.pairs) {
    if (k++ < stats.seam_terms) {
      if (x[p.i] != x[p.j]) stats.seam += p.e01;
    } else if (x[p.i] != 0 && x[p.j] != 0) {
      stats.overlap += p.e11;
    }
  }
  stats.energy = stats.quality + stats.boundary + stats.seam + stats.overlap;
}

}  // namespace

MosaicSelection select_mosaic(const MosaicInput& input, const MosaicParams& params) {
  Stopwatch clock;
  MosaicEnergy e = build_mosaic_energy(input, params);
  MosaicSelection out;
  out.stats = e.stats;
  out.stats.seconds_build = clock.restart();
  std::vector<std::int8_t> x;
  if (const auto flips = submodular_flips(e.energy)) {
    // Two meshes (or overlaps that never close an odd cycle): one exact cut.
    x = minimise_by_flipped_cut(e.energy, *flips);
    out.stats.solver.exact = true;
  } else {
    // Start from nothing kept and let each mesh in turn, oldest first, take the places where
    // it does better than what is kept: every move is an exact cut, none raises the energy.
    // The groups are numbered by date, as the moves visit them.
    std::vector<std::uint32_t> group_of_acquisition(input.meshes.size());
    const std::vector<std::size_t> by_date = mosaic_detail::date_order(input);
    for (std::size_t r = 0; r < by_date.size(); ++r) group_of_acquisition[by_date[r]] = static_cast<std::uint32_t>(r);
    std::vector<std::uint32_t> group(e.triangle_of.size());
    for (std::size_t v = 0; v < group.size(); ++v) {
      group[v] = group_of_acquisition[input.change->index.acquisition_of(e.triangle_of[v])];
    }
    x.assign(e.triangle_of.size(), 0);
    GroupMoveParams moves;
    moves.max_sweeps = std::max(1, params.sweeps);
    moves.coordinate = e.coordinate;
    moves.slabs = slab_count(x.size());
    moves.later_sweep_hops = static_cast<std::uint32_t>(std::max(0, params.later_sweep_reach));
    moves.slabs_at_once = !input.least_memory;
    out.stats.moves = improve_by_group_moves(e.energy, group, x, moves);
  }
  out.stats.seconds_solve = clock.restart();
  out.selected.assign(input.change->index.size(), 0);
  for (std::size_t v = 0; v < x.size(); ++v) out.selected[e.triangle_of[v]] = static_cast<std::uint8_t>(x[v]);
  account(e, x, out.stats);  // the energy of the solver's labelling, before the fill
  // The energy picks passes, not layers: where a pass holds two layers (overlapping turns of
  // a spinning scanner), one stays.
  out.stats.layers_dropped = keep_one_layer(input, 0, out.selected);
  // The energy's answers per global triangle: noted, and given to the fill, which need not
  // ask again (empty when the energy did not ask: the fill then works them out).
  out.notes.assign(input.change->index.size(), 0);
  std::vector<std::uint8_t> seen;
  if (!e.seen_through.empty()) seen.assign(input.change->index.size(), 0);
  for (std::size_t v = 0; v < e.seen_through.size(); ++v) {
    if (e.seen_through[v] == 0) continue;
    seen[e.triangle_of[v]] = 1;
    out.notes[e.triangle_of[v]] |= kNoteSeenThrough;
  }
  if (params.fill_holes) {
    const HoleFillCounts fill = fill_holes(input, out.selected, seen, &out.notes);
    out.stats.filled = fill.added;
    out.stats.fill_seen_through = fill.seen_through;
  }
  out.stats.seconds_fill = clock.restart();
  return out;
}

}  // namespace citymesh
