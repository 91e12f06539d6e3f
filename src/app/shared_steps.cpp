// SPDX-License-Identifier: MIT
#include "shared_steps.h"

#include <memory>
#include <string>

#include "citymesh/core/interrupt.h"
#include "citymesh/core/progress.h"
#include "work_schedule.h"

namespace citymesh::app {

void share_items(Cluster& cluster, std::vector<std::uint64_t> costs, const SharedStep& step,
                 const std::function<void(std::size_t)>& here) {
  const std::size_t n = costs.size();
  std::optional<StageProgress> progress;
  if (!step.progress.empty()) progress.emplace(StageProgressParams{.stage = std::string(step.progress), .total = n});
  WorkSchedule schedule(std::move(costs), std::vector<std::vector<std::size_t>>(n), std::vector<std::uint8_t>(n, 0));
  auto channel = cluster.share(&schedule, [&progress](std::size_t) {
    if (progress) progress->advance();
  });
  work_on_shared_items(*channel, step, here);
}

void work_on_shared_items(WorkChannel& channel, const SharedStep& step, const std::function<void(std::size_t)>& body) {
  const std::string what(step.what);
  run_workers(channel, step.workers, [&](std::size_t i) {
    throw_if_interrupted(what);
    body(i);
  });
}

}  // namespace citymesh::app
