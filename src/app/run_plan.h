// SPDX-License-Identifier: MIT
// `citymesh run --plan`: what a run would do with each tile of the work folder, before it
// processes any: which tiles it would process, which it may keep, which it reuses, and how
// long the tiles would take at the speed of the last run's.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "citymesh/config/config.h"
#include "citymesh/tiler/tile_store.h"
#include "tile_plan.h"

namespace citymesh::app {

/// What the last run's report (run.json) says of its speed.
struct LastRunSpeed {
  /// Thread-seconds per input triangle of the tiles it processed; none when it processed none.
  std::optional<double> seconds_per_triangle{};
  /// The wall time of its final pass (every stage after the tiles').
  std::optional<double> final_pass_seconds{};
};

/// What a run would do with the tiles of `store`.
struct RunPlan {
  std::size_t tiles = 0;
  /// No whole result under the tile's inputs (a pass reaches it that was added, rewritten or
  /// withdrawn since, its result is damaged, or it was never processed): processed.
  std::size_t to_process = 0;
  /// A whole result from the same inputs under another digest: a tile it waits for is redone, or a
  /// pass delivered late renumbered its passes. Kept unless a tile it waits for decides
  /// otherwise about its halo, then processed.
  std::size_t may_be_kept = 0;
  /// A finished result under its digest: reused as it is.
  std::size_t reused = 0;
  /// Input triangles (owned) of the tiles to process, and of those that may be kept.
  std::uint64_t triangles_to_process = 0, triangles_may_be_kept = 0;
  /// Names of the tiles to process, ascending.
  std::vector<std::string> names_to_process{};
  /// How fast the last run went (its run.json in the output folder).
  LastRunSpeed last_run{};
  /// Every tile reused, and the outputs as the last run left them from the same inputs
  /// (outputs_up_to_date): the run would write nothing. Set by the caller.
  bool outputs_up_to_date = false;
};

/// Looks at each tile's result in the work folder under `digests` (their headers only) and
/// at the last run's report; writes nothing.
RunPlan plan_run(const Config& config, const TileStore& store, const TileDigests& digests);

/// The speed the run report `run_json` (run.json's text) gives; nothing when it is not a run
/// report.
LastRunSpeed last_run_speed(const std::string& run_json);

/// The lines `run --plan` prints, the estimate for `threads` threads.
std::string describe_plan(const RunPlan& plan, unsigned threads);

}  // namespace citymesh::app
