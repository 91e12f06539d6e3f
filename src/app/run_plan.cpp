// SPDX-License-Identifier: MIT
#include "run_plan.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <nlohmann/json.hpp>

#include "citymesh/core/read_file.h"
#include "run_stages.h"
#include "tile_job.h"

namespace citymesh::app {

namespace {

/// How many tiles to process `describe_plan` names before "and N more".
constexpr std::size_t kNamesShown = 12;

}  // namespace

LastRunSpeed last_run_speed(const std::string& run_json) {
  LastRunSpeed speed;
  try {
    const nlohmann::json report = nlohmann::json::parse(run_json);
    double seconds = 0;
    std::uint64_t triangles = 0;
    for (const nlohmann::json& tile : report.at("per_tile")) {
      // Reused tiles carry no seconds: their work was done by an earlier run.
      if (!tile.contains("seconds")) continue;
      for (const auto& [step, s] : tile.at("seconds").items()) seconds += s.get<double>();
      triangles += tile.at("owned").get<std::uint64_t>();
    }
    if (triangles > 0) speed.seconds_per_triangle = seconds / static_cast<double>(triangles);
    // A report of `merge` has no tiling or tiles stage: its total is its final pass.
    const nlohmann::json& seconds_of = report.at("seconds");
    speed.final_pass_seconds =
        seconds_of.at("total").get<double>() - seconds_of.value("tiling", 0.0) - seconds_of.value("tiles", 0.0);
    return speed;
  } catch (const nlohmann::json::exception&) {
    return {};  // not a run report (an older format, or damaged): no estimate
  }
}

RunPlan plan_run(const Config& config, const TileStore& store, const TileDigests& digests) {
  RunPlan plan;
  plan.tiles = store.tiles.size();
  for (std::size_t k = 0; k < store.tiles.size(); ++k) {
    const TileContents& tile = store.tiles[k];
    const std::filesystem::path file = result_path(config, tile.key);
    // As the tile stage decides: a finished result under the digest is reused; a whole one
    // from the same inputs is kept when the decisions it keeps are the same
    // (keep_if_still_right); a damaged one is processed again.
    if (tile_result_is_finished(file, digests.result[k], store)) {
      ++plan.reused;
      continue;
    }
    // Its header first: after a change of settings every tile would be read whole for nothing.
    const std::optional<ResultOrigin> origin = tile_result_origin(file);
    if (origin && origin->inputs == digests.inputs[k] && whole_tile_result_origin(file)) {
      ++plan.may_be_kept;
      plan.triangles_may_be_kept += tile.owned();
      continue;
    }
    ++plan.to_process;
    plan.triangles_to_process += tile.owned();
    plan.names_to_process.push_back(tile.key.name());
  }
  if (const std::optional<std::string> text = read_file_bytes(config.project.output / "run.json")) {
    plan.last_run = last_run_speed(*text);
  }
  return plan;
}

std::string describe_plan(const RunPlan& plan, unsigned threads) {
  const std::string may_be_kept = plan.may_be_kept == 0
                                      ? std::string()
                                      : fmt::format(
                                            ", {} kept unless a tile they wait for decides otherwise about their halo "
                                            "({} input triangles)",
                                            plan.may_be_kept, plan.triangles_may_be_kept);
  std::string out = fmt::format("plan: {} tiles: {} to process ({} input triangles){}, {} reused\n", plan.tiles,
                                plan.to_process, plan.triangles_to_process, may_be_kept, plan.reused);
  if (!plan.names_to_process.empty()) {
    const std::size_t shown = std::min(plan.names_to_process.size(), kNamesShown);
    out += fmt::format("plan: to process: {}{}\n",
                       fmt::join(plan.names_to_process.begin(),
                                 plan.names_to_process.begin() + static_cast<std::ptrdiff_t>(shown), ", "),
                       shown < plan.names_to_process.size()
                           ? fmt::format(" and {} more", plan.names_to_process.size() - shown)
                           : std::string());
  }
  const std::string last_final_pass =
      plan.last_run.final_pass_seconds ? fmt::format(" ({:.1f} s in the last run)", *plan.last_run.final_pass_seconds)
                                       : std::string();
  if (plan.last_run.seconds_per_triangle && plan.to_process + plan.may_be_kept > 0) {
    const double per_thread = *plan.last_run.seconds_per_triangle / std::max(threads, 1u);
    const double least = static_cast<double>(plan.triangles_to_process) * per_thread;
    const double most = static_cast<double>(plan.triangles_to_process + plan.triangles_may_be_kept) * per_thread;
    out += fmt::format(
        "plan: the tiles would take {} s on {} thread(s) at the speed of the last run's tiles ({:.2f} µs of a "
        "thread per input triangle); then the final pass, over the whole output{}\n",
        most > least ? fmt::format("{:.1f} to {:.1f}", least, most) : fmt::format("{:.1f}", least), threads,
        *plan.last_run.seconds_per_triangle * 1e6, last_final_pass);
  } else if (plan.to_process + plan.may_be_kept > 0) {
    out += "plan: no estimate of the time: the output folder holds no readable report of a run that processed tiles\n";
  } else if (plan.outputs_up_to_date) {
    out +=
        "plan: every tile's result is reused and the outputs are the last run's, made from the same: the run would "
        "write nothing\n";
  } else {
    out +=
        fmt::format("plan: every tile's result is reused: the run would do the final pass only{}\n", last_final_pass);
  }
  out += "plan: nothing was processed; run the same command without --plan to do it\n";
  return out;
}

}  // namespace citymesh::app
