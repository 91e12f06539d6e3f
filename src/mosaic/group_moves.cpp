// SPDX-License-Identifier: MIT
// Group moves: each mesh in turn re-solved against what is kept, one exact cut per move, the
// cut optionally split into slabs solved in parallel.
#include <algorithm>
#include <cmath>
#include <optional>

#include "citymesh/core/parallel.h"
#include "citymesh/mosaic/binary_energy.h"
#include "restricted_energy.h"

namespace citymesh {

using mosaic_detail::grow_region;
using mosaic_detail::PairIndex;
using mosaic_detail::restricted;
using mosaic_detail::seam_region;
using mosaic_detail::split_by_slab;

namespace {

struct SolveOutcome {
  bool exact = false, improved = false;
};

/// Minimises the energy over the variables in `open` (the others fixed to x): exactly by one
/// cut when the restricted energy flips to submodular, else by QPBO's persistent labels. The
/// new labels replace x's only when they lower the energy. The flips tried first: every
/// variable not in `group` (what a group move's overlap terms need), checked in one pass over
/// the pairs; a search for flips otherwise.
SolveOutcome solve_subset(const BinaryEnergy& e, const PairIndex& index, std::span<const std::uint32_t> open,
                          std::span<const std::uint32_t> group_of, std::uint32_t group, std::vector<std::int8_t>& x,
                          std::vector<std::uint32_t>& to_local) {
  SolveOutcome out;
  if (open.empty()) return {true, false};
  const BinaryEnergy sub = restricted(e, index, x, open, to_local);
  std::vector<std::uint8_t> guess(open.size());
  for (std::size_t l = 0; l < open.size(); ++l) guess[l] = group_of[open[l]] != group ? 1 : 0;
  std::optional<std::vector<std::uint8_t>> flips;
  if (flips_make_submodular(sub, guess)) {
    flips = std::move(guess);
  } else {
    flips = submodular_flips(sub);
  }
  std::vector<std::int8_t> y;
  if (flips) {
    y = minimise_by_flipped_cut(sub, *flips);
    out.exact = true;
  } else {
    y = qpbo(sub);  // persistent labels only; the others keep their value
    for (std::size_t l = 0; l < y.size(); ++l) {
      if (y[l] == kUnlabelled) y[l] = x[open[l]];
    }
  }
  // The restricted energy differs from the whole one by a constant: compare there.
  std::vector<std::int8_t> now(open.size());
  for (std::size_t l = 0; l < open.size(); ++l) now[l] = x[open[l]];
  const auto [before, after] = sub.evaluate(now, y);
  if (after < before - 1e-9 * (1 + std::abs(before))) {
    for (std::size_t l = 0; l < open.size(); ++l) x[open[l]] = y[l];
    out.improved = true;
  }
  return out;
}

/// Slab of every variable: slabs of equal counts along the coordinate (ties stay together).
std::vector<std::uint32_t> slab_of_variables(std::span<const float> coordinate, std::uint32_t slabs) {
  // Each bound is the value a full sort would put at its rank: found by selection, in
  // increasing rank, each within what the previous one left above it.
  std::vector<float> ranked(coordinate.begin(), coordinate.end());
  std::vector<float> bounds;
  auto from = ranked.begin();
  for (std::uint32_t s = 1; s < slabs; ++s) {
    const auto at = ranked.begin() + static_cast<std::ptrdiff_t>(ranked.size() * s / slabs);
    std::nth_element(from, at, ranked.end());
    bounds.push_back(*at);
    from = at;
  }
  std::vector<std::uint32_t> slab(coordinate.size());
  for (std::size_t v = 0; v < slab.size(); ++v) {
    slab[v] =
        static_cast<std::uint32_t>(std::upper_bound(bounds.begin(), bounds.end(), coordinate[v]) - bounds.begin());
  }
  return slab;
}

/// The state shared by the moves of one call.
struct Mover {
  const BinaryEnergy& e;
  std::span<const std::uint32_t> group;
  const GroupMoveParams& params;
  PairIndex index;
  std::vector<std::uint32_t> slab;                   ///< per variable; empty without slabs
  std::vector<std::vector<std::uint32_t>> to_local;  ///< scratch per slab
  std::vector<std::uint8_t> open, mark;              ///< flags per variable

  Mover(const BinaryEnergy& energy, std::span<const std::uint32_t> g, const GroupMoveParams& p)
      : e(energy), group(g), params(p), index(energy), open(energy.size(), 0), mark(energy.size(), 0) {
    const std::uint32_t slabs = params.coordinate.size() == e.size() ? std::max(1u, params.slabs) : 1u;
    if (slabs > 1) slab = slab_of_variables(params.coordinate, slabs);
    to_local.assign(slabs, std::vector<std::uint32_t>(e.size(), UINT32_MAX));
  }

  /// Re-solves group k against the variables at 1 (x changes only where that lowers the
  /// energy), with `near_seams` only those within later_sweep_hops terms of a seam of x;
  /// nullopt when no variable is open.
  std::optional<SolveOutcome> move(std::uint32_t k, std::vector<std::int8_t>& x, GroupMoveStats& stats,
                                   bool near_seams) {
    std::vector<std::uint32_t> all;
    for (std::uint32_t v = 0; v < e.size(); ++v) {
      open[v] = group[v] == k || x[v] == 1 ? 1 : 0;
      if (open[v] != 0) all.push_back(v);
    }
    if (near_seams) {
      std::vector<std::uint32_t> region = seam_region(index, x, all, open, params.later_sweep_hops, mark);
      for (const std::uint32_t v : all) open[v] = 0;
      for (const std::uint32_t v : region) open[v] = 1;
      all = std::move(region);
    }
    if (all.empty()) return std::nullopt;
    SolveOutcome out;
    if (slab.empty()) {
      ++stats.solves;
      out = solve_subset(e, index, all, group, k, x, to_local[0]);
    } else {
      out = move_by_slabs(k, all, x, stats);
    }
    for (const std::uint32_t v : all) open[v] = 0;
    return out;
  }

  /// Slab interiors in parallel (no term joins two of them, so each solve sees the others'
  /// variables only through the border, fixed meanwhile), then the borders.
  SolveOutcome move_by_slabs(std::uint32_t k, std::span<const std::uint32_t> all, std::vector<std::int8_t>& x,
                             GroupMoveStats& stats) {
    auto [interior, border] = split_by_slab(index, all, open, slab, static_cast<std::uint32_t>(to_local.size()));
    std::vector<SolveOutcome> outcomes(interior.size() + 1);
    const auto solve_slabs = [&](std::size_t begin, std::size_t end) {
      for (std::size_t s = begin; s < end; ++s) {
        outcomes[s] = solve_subset(e, index, interior[s], group, k, x, to_local[s]);
      }
    };
    if (params.slabs_at_once) {
      parallel_for_blocks(interior.size(), 1, solve_slabs);
    } else {
      solve_slabs(0, interior.size());
    }
    outcomes.back() = solve_subset(e, index, grow_region(index, std::move(border), open, params.border_hops, mark),
                                   group, k, x, to_local[0]);
    stats.solves += outcomes.size();
    SolveOutcome out{true, false};
    for (const SolveOutcome& o : outcomes) {
      out.exact = out.exact && o.exact;
      out.improved = out.improved || o.improved;
    }
    return out;
  }
};

}  // namespace

GroupMoveStats improve_by_group_moves(const BinaryEnergy& e, std::span<const std::uint32_t> group,
                                      std::vector<std::int8_t>& x, const GroupMoveParams& params) {
  GroupMoveStats stats;
  if (e.size() == 0) return stats;
  Mover mover(e, group, params);
  const std::uint32_t groups = *std::max_element(group.begin(), group.end()) + 1;
  for (int sweep = 0; sweep < std::max(1, params.max_sweeps); ++sweep) {
    ++stats.sweeps;
    bool changed = false;
    for (std::uint32_t k = 0; k < groups; ++k) {
      const std::optional<SolveOutcome> o = mover.move(k, x, stats, sweep > 0 && params.later_sweep_hops > 0);
      if (!o) continue;  // nothing open: no move
      ++stats.moves;
      stats.exact_moves += o->exact ? 1 : 0;
      stats.improving_moves += o->improved ? 1 : 0;
      changed = changed || o->improved;
    }
    if (!changed) break;
  }
  return stats;
}

}  // namespace citymesh
