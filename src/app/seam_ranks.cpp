// SPDX-License-Identifier: MIT
#include "seam_ranks.h"

#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>

#include "citymesh/core/atomic_file.h"
#include "citymesh/core/error.h"
#include "citymesh/core/interrupt.h"
#include "citymesh/core/log.h"
#include "citymesh/core/parallel.h"
#include "json_bits.h"
#include "mosaic_step.h"
#include "seam_cache.h"
#include "shared_steps.h"
#include "work_schedule.h"

namespace citymesh::app {

namespace {

/// The plan of the step being shared, written by the root before it shares the step.
std::filesystem::path plan_path(const Config& config) { return config.project.work / "seam-level.json"; }

constexpr std::string_view kOutcomeSuffix = "outcome.json";

/// The plan another rank needs for one step: the root's folder, every part as the step sees
/// it, the sources' sizes (clipping's precedence) and what to do with the parts: measure
/// their open boundary (before or after stitching) or stitch those of one level.
struct StepPlan {
  std::filesystem::path dir;
  std::string step;       ///< "measure" or "stitch"
  int level = 0;          ///< stitch: the level
  bool stitched = false;  ///< measure: after stitching
  std::vector<BlockPart> parts;
  std::vector<std::uint64_t> source_sizes;
};

void write_plan(const Config& config, const StepPlan& plan) {
  nlohmann::json parts = nlohmann::json::array();
  for (const BlockPart& p : plan.parts) {
    parts.push_back(
        {{"key", block_part_key_json(p.key)}, {"box", box_bits(p.box)}, {"stitched_box", box_bits(p.stitched_box)}});
  }
  const nlohmann::json j{{"dir", std::filesystem::absolute(plan.dir).string()},
                         {"step", plan.step},
                         {"level", plan.level},
                         {"stitched", plan.stitched},
                         {"parts", parts},
                         {"source_sizes", plan.source_sizes}};
  write_file_atomically(plan_path(config), j.dump() + "\n");
}

StepPlan read_plan(const Config& config) {
  return decode_json_file(plan_path(config), "rank 0's plan of the seam pass", [](const nlohmann::json& j) {
    StepPlan plan;
    plan.dir = j.at("dir").get<std::string>();
    plan.step = j.at("step").get<std::string>();
    plan.level = j.at("level").get<int>();
    plan.stitched = j.at("stitched").get<bool>();
    for (const auto& p : j.at("parts")) {
      const auto& key = p.at("key");
      plan.parts.push_back({block_part_key_from(key), box_from_bits(p.at("box")), box_from_bits(p.at("stitched_box"))});
    }
    plan.source_sizes = j.at("source_sizes").get<std::vector<std::uint64_t>>();
    return plan;
  });
}

/// A part's open boundary as its bits (the sum must come out the same as on one process).
nlohmann::json length_json(double metres) { return {{"bits", double_bits(metres)}}; }
double length_from(const nlohmann::json& j) { return double_from_bits(j.at("bits")); }

constexpr std::string_view kLengthSuffix = "length.json";

/// A step of the seam pass on every rank: at most kMaxSeamPartsInFlight parts at a time.
SharedStep seam_step() {
  return {.workers = std::min(available_threads(), kMaxSeamPartsInFlight), .what = "the seam pass", .progress = {}};
}

/// Hands out one item per entry of `index` (item i: part index[i]) to every rank's workers,
/// largest part file first (once stitched, the input files are gone: then in part order);
/// `here(i)` does one on this rank. Returns once every rank's workers are done.
void share_items(Cluster& cluster, const SeamPartFiles& files, std::span<const std::size_t> index,
                 const std::function<void(std::size_t)>& here) {
  std::vector<std::uint64_t> costs;  // largest first, as tiles: none is left to end a step alone
  for (const std::size_t p : index) costs.push_back(files.input_bytes(p));
  app::share_items(cluster, std::move(costs), seam_step(), here);
}

}  // namespace

SeamPassWork share_seam_pass(const Config& config, Cluster& cluster, const SeamPartFiles& files) {
  const std::vector<std::uint64_t> sizes = files.source_sizes();
  SeamPassWork work;
  work.measure_parts = [&config, &cluster, &files, sizes](const BoundaryMeasurer& measurer) {
    const StepPlan plan{
        files.dir(), "measure", 0, measurer.stitched(), {measurer.parts().begin(), measurer.parts().end()}, sizes};
    write_plan(config, plan);
    std::vector<std::size_t> all(measurer.size());
    for (std::size_t p = 0; p < all.size(); ++p) all[p] = p;
    std::vector<std::optional<double>> here(all.size());
    share_items(cluster, files, all, [&](std::size_t p) { here[p] = measurer.measure(p); });
    std::vector<double> lengths(all.size());
    for (std::size_t p = 0; p < all.size(); ++p) {
      lengths[p] = here[p]
                       ? *here[p]
                       : take_json_file(files.beside(p, kLengthSuffix), "a part another rank measured", length_from);
    }
    return lengths;
  };
  work.run_level = [&config, &cluster, &files, sizes](const LevelStitcher& level) {
    const StepPlan plan{files.dir(), "stitch", level.level(), false, {level.parts().begin(), level.parts().end()},
                        sizes};
    write_plan(config, plan);
    std::vector<std::optional<PartOutcome>> here(level.size());
    share_items(cluster, files, level.parts_of_level(), [&](std::size_t i) { here[i] = level.stitch(i); });
    std::vector<PartOutcome> outcomes(level.size());
    std::size_t elsewhere = 0;
    for (std::size_t i = 0; i < level.size(); ++i) {
      if (here[i]) {
        outcomes[i] = *here[i];
        continue;
      }
      outcomes[i] = take_json_file(files.beside(level.parts_of_level()[i], kOutcomeSuffix),
                                   "a part another rank stitched", outcome_from);
      ++elsewhere;
    }
    log::debug("seam pass: level {}: {} of {} parts stitched by other ranks", level.level(), elsewhere, level.size());
    return outcomes;
  };
  return work;
}

void remove_seam_plan(const Config& config) {
  std::error_code ec;
  std::filesystem::remove(plan_path(config), ec);
}

void help_seam_pass(const Config& config, Cluster& cluster) {
  std::atomic<std::size_t> stitched = 0, reused = 0, measured = 0;
  SeamPartCache cache = seam_part_cache(config);
  // Outlives every measurer, which keeps a reference to it: a temporary made the other ranks
  // measure with a grid already gone (their lengths, and the run's open boundary, were wrong).
  const BlockStitchParams blocks = tile_grid_blocks(config);
  // The root's steps: the boundary measured, the levels stitched, the boundary measured again.
  for (int step = 0; step < kBlockStitchLevels + 2; ++step) {
    // The root writes the plan before it shares the step, and sharing starts with a barrier.
    auto channel = cluster.share(nullptr, {});
    const StepPlan plan = read_plan(config);
    const bool measuring = step == 0 || step == kBlockStitchLevels + 1;
    if (plan.step != (measuring ? "measure" : "stitch") || (!measuring && plan.level != step - 1)) {
      throw ProcessingError(fmt::format("{}: step '{}' (level {}) where step {} of the seam pass was expected",
                                        plan_path(config).string(), plan.step, plan.level, step));
    }
    std::vector<BlockPartKey> keys;
    for (const BlockPart& p : plan.parts) keys.push_back(p.key);
    SeamPartFiles files(plan.dir, std::move(keys));
    // Each part's result is written before the root hears that the part is done (the
    // worker's next request says so).
    if (measuring) {
      const BoundaryMeasurer measurer(plan.parts, files, plan.stitched, blocks);
      work_on_shared_items(*channel, seam_step(), [&](std::size_t p) {
        write_file_atomically(files.beside(p, kLengthSuffix), length_json(measurer.measure(p)).dump());
        ++measured;
      });
      continue;
    }
    const PartStitchRun run{.params = stitch_params(config),
                            .blocks = blocks,
                            .source_sizes = plan.source_sizes,
                            .frame = std::nullopt,
                            .run_level = {},
                            .cache = &cache};
    const LevelStitcher stitcher(plan.parts, plan.level, files, run);
    work_on_shared_items(*channel, seam_step(), [&](std::size_t i) {
      const PartOutcome outcome = stitcher.stitch(i);
      write_file_atomically(files.beside(stitcher.parts_of_level()[i], kOutcomeSuffix), outcome_json(outcome).dump());
      ++(outcome.reused ? reused : stitched);
    });
  }
  log::info("rank {}: stitched {} parts of the seam pass, took {} as the last run stitched them, and measured {}",
            cluster.rank(), stitched.load(), reused.load(), measured.load());
}

}  // namespace citymesh::app
