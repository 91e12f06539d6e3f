// SPDX-License-Identifier: MIT
#include "pipeline.h"

#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <iostream>

#include "citymesh/core/stopwatch.h"
#include "detect_output.h"
#include "leftovers.h"

namespace citymesh::app {

namespace {

void report(const ChangeResult& r, const std::filesystem::path& dir) {
  const StateCounts c = count_states(r, 0, r.index.size());
  const ChangeStats& s = r.stats;
  std::cout << fmt::format("{}: {} triangles: {} consistent, {} conflicting, {} single; {} kept\n", dir.string(),
                           s.triangles, c.state[0], c.state[1], c.state[2], c.kept);
  std::cout << fmt::format("  {} consistent pairs; pre-filter skipped {} of {} candidates ({:.1f} %), {} exact tests\n",
                           s.consistent_pairs, s.prefilter_skipped, s.conflict_candidates, 100 * s.prefilter_hit_rate(),
                           s.exact_tests);
  std::cout << fmt::format("  {:.3f} s: consistency {:.3f}, grids {:.3f}, conflicts {:.3f}, time series {:.3f}\n",
                           s.seconds_total(), s.seconds_consistency, s.seconds_grids, s.seconds_conflicts,
                           s.seconds_time_series);
}

}  // namespace

void PipelineOptions::declare(CLI::App& app) {
  app.add_option("config", config, "the run's config file")->required()->check(CLI::ExistingFile);
  app.add_option("--set", overrides, "override a key, as section.key=value (repeatable)");
  app.add_option("--threads", threads, "worker threads (default: [run] threads; 0: all cores)");
  app.add_option("--pixel", pixel_size, "metres per pixel of the pictures")->check(CLI::Range(0.005, 100.0));
  app.add_flag("--no-pictures", no_pictures, "skip the PNGs");
}

Config PipelineOptions::load() const { return load_config(config, {.overrides = overrides, .check_files = true}); }

DetectStep run_detect_step(const Config& config, const PictureOptions& pictures) {
  DetectStep step;
  Stopwatch clock;
  remove_leftovers_of_ended_runs(config);
  step.input = load_acquisitions(config);
  step.read_seconds = clock.restart();
  step.result = detect_changes({step.input.meshes, step.input.dates}, config.change);
  step.detect_seconds = clock.restart();
  const std::filesystem::path dir = config.project.output / "detect";
  InMemoryDetectOutput source(step.input, step.result);
  std::vector<std::uint64_t> vertices;
  for (const Mesh& m : step.input.meshes) vertices.push_back(m.vertex_count());
  write_detect_outputs(config, step.input, source,
                       {.dir = dir,
                        .pixel_size = pictures.pixel_size,
                        .pictures = pictures.pictures,
                        .read_seconds = step.read_seconds,
                        .at_once = labelled_outputs_at_once(vertices, InMemoryDetectOutput::kBytesPerVertex,
                                                            pictures.pictures, config.run.memory)});
  step.write_seconds = clock.restart();
  report(step.result, dir);
  return step;
}

}  // namespace citymesh::app
