// SPDX-License-Identifier: MIT
// detect_changes: the steps in order, then the time series.
#include "citymesh/change/detect.h"

#include <algorithm>

#include "citymesh/core/log.h"
#include "citymesh/core/parallel.h"
#include "citymesh/core/stopwatch.h"
#include "frames.h"

namespace citymesh {

using namespace change_detail;

namespace {

/// True when a newer acquisition's empty space reaches the voxels of triangle g: a newer pass
/// looked at this place.
bool observed_later(const TriangleFrames& f, std::size_t g, std::span<const OccupancyGrid> grids) {
  const TimePoint date = f.date_of(g);
  const Box3f box = f.bounds(g);
  for (std::size_t j = 0; j < grids.size(); ++j) {
    if (date < f.dates[j] && grids[j].any_in_box(box.min, box.max)) return true;
  }
  return false;
}

/// first/last seen over each triangle and its consistent partners, sustainability, state and
/// the keep decision under the unconfirmed policy.
void compute_time_series(const TriangleFrames& f, const PartnerBits& partners, const ConflictFlags& conflicts,
                         std::span<const OccupancyGrid> grids, const ChangeParams& params, ChangeResult& r) {
  const std::size_t n = f.size();
  r.first_seen.resize(n);
  r.last_seen.resize(n);
  for (std::size_t g = 0; g < n; ++g) r.first_seen[g] = r.last_seen[g] = f.date_of(g);
  for (const auto& [a, b] : r.consistent_pairs) {
    const TimePoint da = f.date_of(a), db = f.date_of(b);
    r.first_seen[a] = std::min(r.first_seen[a], db);
    r.last_seen[a] = std::max(r.last_seen[a], db);
    r.first_seen[b] = std::min(r.first_seen[b], da);
    r.last_seen[b] = std::max(r.last_seen[b], da);
  }
  r.state.resize(n);
  r.sustainable.resize(n);
  r.kept.resize(n);
  parallel_for_blocks(n, 16384, [&](std::size_t begin, std::size_t end) {
    for (std::size_t g = begin; g < end; ++g) {
      r.sustainable[g] = r.last_seen[g] - r.first_seen[g] >= params.sustainability ? 1 : 0;
      if (!f.asks(g)) {
        r.state[g] = TriangleState::single;
        r.kept[g] = 0;
        continue;
      }
      if (conflicts.conflicting[g] != 0) {
        r.state[g] = TriangleState::conflicting;
        r.kept[g] = 0;
        continue;
      }
      r.state[g] = partners.any(g) ? TriangleState::consistent : TriangleState::single;
      bool keep = r.sustainable[g] != 0;
      if (!keep) {
        switch (params.unconfirmed) {
          case UnconfirmedPolicy::drop:
            break;
          case UnconfirmedPolicy::keep:
            keep = true;
            break;
          case UnconfirmedPolicy::keep_unobserved:
            keep = !observed_later(f, g, grids);
            break;
        }
      }
      r.kept[g] = keep ? 1 : 0;
    }
  });
}

}  // namespace

LabelView label_view(const ChangeResult& r, std::size_t begin, std::size_t end) {
  const std::size_t n = end - begin;
  return {std::span(r.state).subspan(begin, n),     std::span(r.first_seen).subspan(begin, n),
          std::span(r.last_seen).subspan(begin, n), std::span(r.sustainable).subspan(begin, n),
          std::span(r.kept).subspan(begin, n),      std::span(r.refutes).subspan(begin, n)};
}

StateCounts& StateCounts::operator+=(const StateCounts& o) {
  for (std::size_t s = 0; s < state.size(); ++s) state[s] += o.state[s];
  kept += o.kept;
  sustainable += o.sustainable;
  refutes += o.refutes;
  return *this;
}

StateCounts count_states(const LabelView& labels) {
  StateCounts c;
  for (std::size_t t = 0; t < labels.size(); ++t) {
    ++c.state[static_cast<std::size_t>(labels.state[t])];
    c.kept += labels.kept[t];
    c.sustainable += labels.sustainable[t];
    c.refutes += labels.refutes[t];
  }
  return c;
}

StateCounts count_states(const ChangeResult& r, std::size_t begin, std::size_t end) {
  return count_states(label_view(r, begin, end));
}

ChangeResult detect_changes(const ChangeInput& input, const ChangeParams& params) {
  ChangeResult r;
  Stopwatch clock;
  const TriangleFrames frames = prepare_triangles(input, params);
  r.index = frames.index;
  r.stats.triangles = frames.size();
  r.stats.seconds_prepare = clock.restart();

  OverlappingPairs pairs = find_overlapping_pairs(frames, params, r.stats);
  r.consistent_pairs = std::move(pairs.consistent);
  r.layer_pairs = std::move(pairs.layers);
  r.stats.seconds_consistency = clock.restart();

  const bool need_grids = params.prefilter || params.unconfirmed == UnconfirmedPolicy::keep_unobserved;
  std::vector<OccupancyGrid> grids;
  if (need_grids) grids = build_empty_space_grids(frames, params, asked_voxels(frames, params.voxel_size), r.stats);
  r.stats.seconds_grids = clock.restart();

  const PartnerBits partners = partner_bits(frames, r.consistent_pairs);
  ConflictFlags conflicts = find_conflicts(frames, partners, grids, params, r.stats);
  r.stats.seconds_conflicts = clock.restart();

  compute_time_series(frames, partners, conflicts, grids, params, r);
  r.refutes = std::move(conflicts.refutes);
  r.stats.seconds_time_series = clock.restart();
  log::debug("change detection: {} triangles, {} pairs, {} pairs of layers of one pass, {} exact tests, {:.3f} s",
             r.stats.triangles, r.stats.consistent_pairs, r.layer_pairs.size(), r.stats.exact_tests,
             r.stats.seconds_total());
  return r;
}

}  // namespace citymesh
