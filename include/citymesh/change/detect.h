// SPDX-License-Identifier: MIT
// Change detection and time series (paper section III) on one in-memory set of meshes: which
// triangles agree between acquisitions (consistent), which belong to surfaces that have
// disappeared (conflicting), and which are sustainable. A tile with its halo is such a set.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <span>
#include <string_view>
#include <utility>
#include <vector>

#include "citymesh/change/change_params.h"
#include "citymesh/core/mesh.h"
#include "citymesh/core/packed_pairs.h"
#include "citymesh/core/time.h"

namespace citymesh {

/// What the caller wants of a triangle. A tile holds its own triangles, copies of its
/// neighbours' near its border (their labels give the tile's mosaic its context) and copies of
/// triangles whose empty space crosses it (to find the conflicts they cause there).
enum class TriangleUse : std::uint8_t {
  /// Its labels; its conflicts raise the `refutes` of the newer triangles they come from.
  labelled = 0,
  /// Its labels; its conflicts raise no `refutes` (the caller counts them where it is labelled).
  context = 1,
  /// Only its empty space: it asks nothing (no consistency query, no conflict test of its
  /// own); only its `refutes` is meaningful, and it is never kept.
  empty_space = 2,
};

/// The meshes of every acquisition, index = acquisition index (a run gives them by time), all in one local
/// frame (the same origin) and with sensor positions; dates may come in any order.
struct ChangeInput {
  std::span<const Mesh> meshes;
  std::span<const TimePoint> dates;  ///< one per mesh
  /// Per global triangle (see GlobalTriangles); empty: every triangle is labelled.
  std::span<const TriangleUse> uses = {};
};

enum class TriangleState : std::uint8_t { consistent = 0, conflicting = 1, single = 2 };
[[nodiscard]] std::string_view triangle_state_name(TriangleState s);

/// Triangles are numbered globally: acquisition a's triangle t is offsets[a] + t.
struct GlobalTriangles {
  std::vector<std::size_t> offsets;  ///< size meshes + 1
  [[nodiscard]] std::size_t size() const { return offsets.back(); }
  /// Inline: the tile job asks it several times per pair (out of line it was 4.6 % of a
  /// tile's instructions).
  [[nodiscard]] std::uint32_t acquisition_of(std::size_t g) const {
    return static_cast<std::uint32_t>(std::upper_bound(offsets.begin(), offsets.end(), g) - offsets.begin() - 1);
  }
};

/// Consistent pairs (global indices, first < second), sorted: the overlap edges of the mosaic.
using TrianglePair = std::pair<std::uint32_t, std::uint32_t>;

struct ChangeStats {
  std::uint64_t triangles = 0;
  std::uint64_t consistent_pairs = 0;
  std::uint64_t conflict_candidates = 0;  ///< (triangle, newer acquisition) pairs without consistency
  std::uint64_t prefilter_skipped = 0;    ///< of those, ruled out by the empty-space grids
  std::uint64_t exact_tests = 0;          ///< triangle-tetrahedron tests run
  std::uint64_t marked_voxels = 0;
  double seconds_prepare = 0, seconds_consistency = 0, seconds_grids = 0, seconds_conflicts = 0,
         seconds_time_series = 0;
  [[nodiscard]] double prefilter_hit_rate() const {
    return conflict_candidates == 0 ? 0.0 : double(prefilter_skipped) / double(conflict_candidates);
  }
  [[nodiscard]] double seconds_total() const {
    return seconds_prepare + seconds_consistency + seconds_grids + seconds_conflicts + seconds_time_series;
  }
  /// Adds another run's figures (a tiled run sums its tiles').
  void add(const ChangeStats& other);
};

/// ChangeStats' counts and seconds, for code that treats every figure alike (sums, files).
/// Tile result files store them in this order: append, never reorder.
inline constexpr std::array kChangeCounts{&ChangeStats::triangles,           &ChangeStats::consistent_pairs,
                                          &ChangeStats::conflict_candidates, &ChangeStats::prefilter_skipped,
                                          &ChangeStats::exact_tests,         &ChangeStats::marked_voxels};
inline constexpr std::array kChangeSeconds{&ChangeStats::seconds_prepare, &ChangeStats::seconds_consistency,
                                           &ChangeStats::seconds_grids, &ChangeStats::seconds_conflicts,
                                           &ChangeStats::seconds_time_series};

inline void ChangeStats::add(const ChangeStats& other) {
  for (const auto field : kChangeCounts) this->*field += other.*field;
  for (const auto field : kChangeSeconds) this->*field += other.*field;
}

struct ChangeResult {
  GlobalTriangles index;
  std::vector<TriangleState> state;  ///< per global triangle
  std::vector<TimePoint> first_seen, last_seen;
  std::vector<std::uint8_t> sustainable;  ///< last_seen - first_seen >= Ts
  std::vector<std::uint8_t> kept;         ///< survives the time series (not conflicting; sustainable or
                                          ///< kept by the unconfirmed policy)
  std::vector<std::uint8_t> refutes;      ///< its empty space made an older labelled triangle conflict
  /// Sorted, first < second; packed (2.3 bytes a pair on a spinning street instead of 8).
  PackedPairs consistent_pairs;
  /// Overlapping triangles of one acquisition that share no corner (sorted, first < second):
  /// two layers of one pass, such as the overlapping turns of a spinning scanner meshed one
  /// by one. They take no part in the labels; the mosaic keeps at most one of each pair.
  PackedPairs layer_pairs;
  ChangeStats stats;
};

/// The labels of a run of triangles (one acquisition's, usually): views into a ChangeResult,
/// or into labels a tiled run expands one acquisition at a time.
struct LabelView {
  std::span<const TriangleState> state;
  std::span<const TimePoint> first_seen, last_seen;
  std::span<const std::uint8_t> sustainable, kept, refutes;
  [[nodiscard]] std::size_t size() const { return state.size(); }
};

/// The labels of global triangles [begin, end) of `result`.
LabelView label_view(const ChangeResult& result, std::size_t begin, std::size_t end);

/// Triangles per state, kept, sustainable and refuting.
struct StateCounts {
  std::array<std::uint64_t, 3> state{};  ///< indexed by TriangleState
  std::uint64_t kept = 0, sustainable = 0, refutes = 0;
  StateCounts& operator+=(const StateCounts& o);
};
StateCounts count_states(const LabelView& labels);
/// Over global triangles [begin, end).
StateCounts count_states(const ChangeResult& result, std::size_t begin, std::size_t end);

/// Runs consistency, conflicts and the time series. Same input and params give the same
/// result whatever the thread count. Throws ProcessingError when the meshes lack sensor
/// positions, have different origins, or dates are missing.
ChangeResult detect_changes(const ChangeInput& input, const ChangeParams& params);

}  // namespace citymesh
