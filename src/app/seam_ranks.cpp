// SPDX-License-Identifier: MIT
#include "seam_ranks.h"

#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <bit>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>

#include "citymesh/core/atomic_file.h"
#include "citymesh/core/error.h"
#include "citymesh/core/interrupt.h"
#include "citymesh/core/log.h"
#include "citymesh/core/parallel.h"
#include "mosaic_step.h"
#include "work_schedule.h"

namespace citymesh::app {

namespace {

/// At most this many parts per rank are stitched at a time (their memory, as on one process).
constexpr unsigned kMaxPartsInFlight = 16;

/// The plan of the level being stitched, written by the root before it shares the level.
std::filesystem::path plan_path(const Config& config) { return config.project.work / "seam-level.json"; }

/// Doubles travel as their bits: a part's box sets its stitching frame, so it must come back
/// exactly (and an empty box is infinite).
nlohmann::json box_bits(const Box3d& b) {
  nlohmann::json out = nlohmann::json::array();
  for (const double v : {b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z}) out.push_back(std::bit_cast<std::uint64_t>(v));
  return out;
}

Box3d box_from_bits(const nlohmann::json& j) {
  const auto at = [&](std::size_t k) { return std::bit_cast<double>(j.at(k).get<std::uint64_t>()); };
  Box3d b;
  b.min = {at(0), at(1), at(2)};
  b.max = {at(3), at(4), at(5)};
  return b;
}

/// The counts stitch_parts() adds up, the part's stitched box and its size with surroundings.
nlohmann::json outcome_json(const PartOutcome& o) {
  const StitchStats& s = o.stats;
  return {{"counts",
           {s.vertices_snapped, s.edges_split, s.triangles_uncovered, s.triangles_clipped, s.strips, s.triangles_added,
            s.vertices_welded, s.gaps_filled, s.rejected}},
          {"box", box_bits(o.box)},
          {"cut_triangles", o.cut_triangles}};
}

PartOutcome outcome_from(const nlohmann::json& j) {
  PartOutcome o;
  const auto counts = j.at("counts").get<std::vector<std::uint64_t>>();
  if (counts.size() != 9) throw ProcessingError("a seam part's outcome: counts missing");
  StitchStats& s = o.stats;
  s.vertices_snapped = counts[0], s.edges_split = counts[1], s.triangles_uncovered = counts[2];
  s.triangles_clipped = counts[3], s.strips = counts[4], s.triangles_added = counts[5];
  s.vertices_welded = counts[6], s.gaps_filled = counts[7], s.rejected = counts[8];
  o.box = box_from_bits(j.at("box"));
  o.cut_triangles = j.at("cut_triangles").get<std::size_t>();
  return o;
}

constexpr std::string_view kOutcomeSuffix = "outcome.json";

PartOutcome read_outcome(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw ProcessingError(fmt::format("{}: missing (a part another rank stitched)", file.string()));
  try {
    return outcome_from(nlohmann::json::parse(in));
  } catch (const nlohmann::json::exception& e) {
    throw ProcessingError(fmt::format("{}: malformed ({})", file.string(), e.what()));
  }
}

/// The plan another rank needs: the root's folder, the level, every part as the level sees
/// it, and the sources' sizes (clipping's precedence).
struct LevelPlan {
  std::filesystem::path dir;
  int level = 0;
  std::vector<BlockPart> parts;
  std::vector<std::uint64_t> source_sizes;
};

void write_plan(const Config& config, const SeamPartFiles& files, const LevelStitcher& level,
                std::span<const std::uint64_t> source_sizes) {
  nlohmann::json parts = nlohmann::json::array();
  for (const BlockPart& p : level.parts()) {
    parts.push_back({{"key", {p.key.level, p.key.x, p.key.y}}, {"box", box_bits(p.box)}, {"stitched_box", box_bits(p.stitched_box)}});
  }
  const nlohmann::json plan{{"dir", files.dir().string()},
                            {"level", level.level()},
                            {"parts", parts},
                            {"source_sizes", std::vector<std::uint64_t>(source_sizes.begin(), source_sizes.end())}};
  write_file_atomically(plan_path(config), plan.dump() + "\n");
}

LevelPlan read_plan(const Config& config) {
  const std::filesystem::path file = plan_path(config);
  std::ifstream in(file);
  if (!in) throw ProcessingError(fmt::format("{}: missing (rank 0's plan of the seam pass)", file.string()));
  try {
    const nlohmann::json j = nlohmann::json::parse(in);
    LevelPlan plan;
    plan.dir = j.at("dir").get<std::string>();
    plan.level = j.at("level").get<int>();
    for (const auto& p : j.at("parts")) {
      const auto& key = p.at("key");
      plan.parts.push_back({{key.at(0).get<int>(), key.at(1).get<std::int64_t>(), key.at(2).get<std::int64_t>()},
                            box_from_bits(p.at("box")),
                            box_from_bits(p.at("stitched_box"))});
    }
    plan.source_sizes = j.at("source_sizes").get<std::vector<std::uint64_t>>();
    return plan;
  } catch (const nlohmann::json::exception& e) {
    throw ProcessingError(fmt::format("{}: malformed ({})", file.string(), e.what()));
  }
}

unsigned part_workers() { return std::min(available_threads(), kMaxPartsInFlight); }

}  // namespace

decltype(PartStitchRun::run_level) share_seam_levels(const Config& config, Cluster& cluster,
                                                     const SeamPartFiles& files,
                                                     std::span<const std::uint64_t> source_sizes) {
  return [&config, &cluster, &files, source_sizes](const LevelStitcher& level) {
    write_plan(config, files, level, source_sizes);
    // Largest part first, as tiles: none is left to end the level alone.
    std::vector<std::uint64_t> costs;
    for (const std::size_t p : level.parts_of_level()) costs.push_back(files.input_bytes(p));
    WorkSchedule schedule(std::move(costs), std::vector<std::vector<std::size_t>>(level.size()),
                          std::vector<std::uint8_t>(level.size(), 0));
    std::vector<std::optional<PartOutcome>> here(level.size());
    {
      auto channel = cluster.share(&schedule, [](std::size_t) {});
      run_workers(*channel, part_workers(), [&](std::size_t i) {
        throw_if_interrupted("the seam pass");
        here[i] = level.stitch(i);
      });
    }  // every rank's workers have stopped: their outcomes are written
    std::vector<PartOutcome> outcomes(level.size());
    std::size_t elsewhere = 0;
    for (std::size_t i = 0; i < level.size(); ++i) {
      if (here[i]) {
        outcomes[i] = *here[i];
        continue;
      }
      const std::filesystem::path file = files.beside(level.parts_of_level()[i], kOutcomeSuffix);
      outcomes[i] = read_outcome(file);
      std::filesystem::remove(file);
      ++elsewhere;
    }
    log::debug("seam pass: level {}: {} of {} parts stitched by other ranks", level.level(), elsewhere, level.size());
    return outcomes;
  };
}

void remove_seam_plan(const Config& config) {
  std::error_code ec;
  std::filesystem::remove(plan_path(config), ec);
}

void help_seam_pass(const Config& config, Cluster& cluster) {
  const PartStitchRun run{.params = stitch_params(config),
                          .blocks = tile_grid_blocks(config),
                          .source_sizes = {},
                          .frame = std::nullopt,
                          .run_level = {}};
  std::atomic<std::size_t> stitched = 0;
  for (int level = 0; level < kBlockStitchLevels; ++level) {
    // The root writes the plan before it shares the level, and sharing starts with a barrier.
    auto channel = cluster.share(nullptr, {});
    const LevelPlan plan = read_plan(config);
    if (plan.level != level) {
      throw ProcessingError(fmt::format("{}: level {} where {} was expected", plan_path(config).string(), plan.level, level));
    }
    std::vector<BlockPartKey> keys;
    for (const BlockPart& p : plan.parts) keys.push_back(p.key);
    SeamPartFiles files(plan.dir, std::move(keys));
    PartStitchRun level_run = run;
    level_run.source_sizes = plan.source_sizes;
    const LevelStitcher stitcher(plan.parts, plan.level, files, level_run);
    run_workers(*channel, part_workers(), [&](std::size_t i) {
      throw_if_interrupted("the seam pass");
      const PartOutcome outcome = stitcher.stitch(i);
      // Written before the root hears that the part is done (the next request says so).
      write_file_atomically(files.beside(stitcher.parts_of_level()[i], kOutcomeSuffix), outcome_json(outcome).dump());
      ++stitched;
    });
  }
  log::info("rank {}: stitched {} parts of the seam pass", cluster.rank(), stitched.load());
}

}  // namespace citymesh::app
