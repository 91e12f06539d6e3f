// SPDX-License-Identifier: MIT
// One step of a final pass shared by the ranks of an MPI job: its items handed out by rank 0
// to the worker threads of every rank, each rank leaving what it made for rank 0 to gather in
// item order. The assembly, the seam pass and the outputs share their steps this way.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string_view>
#include <vector>

#include "citymesh/core/log.h"
#include "cluster.h"

namespace citymesh::app {

/// What share_items() needs besides the items' costs.
struct SharedStep {
  unsigned workers = 1;   ///< worker threads on this rank
  std::string_view what;  ///< names the step when an interruption stops it: "the seam pass"
  /// Non-empty: progress lines count the items done by every rank under this name.
  std::string_view progress;
};

/// Hands out one item per cost, largest first, to the worker threads of every rank (the other
/// ranks pull them); `here(i)` does item i in this process. Returns once every rank's workers
/// are done. Collective.
void share_items(Cluster& cluster, std::vector<std::uint64_t> costs, const SharedStep& step,
                 const std::function<void(std::size_t)>& here);

/// A helping rank's side of share_items(): this rank's `step.workers` threads take items from
/// `channel` (shared by the root with the same step) and do `body(i)` for each, stopping
/// between items when interrupted. Root and helpers derive their workers and the step's name
/// from one SharedStep.
void work_on_shared_items(WorkChannel& channel, const SharedStep& step, const std::function<void(std::size_t)>& body);

/// share_items() for items with a result: each item's, from `here(i)` where this rank did it,
/// else from `theirs(i)` (what another rank left for it). Logs how many others did, as `done`
/// ("leaves mapped").
template <class Result>
std::vector<Result> share_and_gather(Cluster& cluster, std::vector<std::uint64_t> costs, const SharedStep& step,
                                     std::string_view done, const std::function<Result(std::size_t)>& here,
                                     const std::function<Result(std::size_t)>& theirs) {
  std::vector<std::optional<Result>> mine(costs.size());
  share_items(cluster, std::move(costs), step, [&](std::size_t i) { mine[i] = here(i); });
  std::vector<Result> out(mine.size());
  std::size_t elsewhere = 0;
  for (std::size_t i = 0; i < out.size(); ++i) {
    if (mine[i]) {
      out[i] = std::move(*mine[i]);
    } else {
      out[i] = theirs(i);
      ++elsewhere;
    }
  }
  log::debug("final pass: {} of {} {} by other ranks", elsewhere, out.size(), done);
  return out;
}

}  // namespace citymesh::app
