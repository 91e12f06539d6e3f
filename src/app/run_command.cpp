// SPDX-License-Identifier: MIT
// `citymesh run CONFIG`: every step: change detection, mosaic, output.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <iostream>

#include "citymesh/config/config.h"
#include "citymesh/core/parallel.h"
#include "citymesh/core/stopwatch.h"
#include "citymesh/mosaic/merged_mesh.h"
#include "citymesh/mosaic/mosaic.h"
#include "citymesh/mosaic/stitch.h"
#include "command.h"
#include "mosaic_output.h"
#include "pipeline.h"

namespace citymesh::app {

namespace {

/// Strip corners closer than this many distance thresholds are welded (5 mm at 10 cm).
constexpr double kWeldInThresholds = 0.05;

MosaicSelection select(const Config& config, const DetectStep& d) {
  const MosaicInput input{d.input.meshes, d.input.dates, &d.result, config.change.distance_threshold};
  return config.mosaic.method == MosaicMethod::update_model ? select_update_model(input)
                                                            : select_mosaic(input, config.mosaic);
}

void report(const std::filesystem::path& dir, const MergedMesh& merged, const MosaicStats& s) {
  std::cout << fmt::format("{}: {} triangles kept of {} candidates", dir.string(), merged.mesh.triangle_count(),
                           s.candidates);
  if (s.seam_terms + s.overlap_terms > 0) {
    std::cout << fmt::format("; energy {:.1f} (quality {:.1f}, boundary {:.1f}, seams {:.1f}, overlaps {:.1f})",
                             s.energy, s.quality, s.boundary, s.seam, s.overlap);
  }
  std::cout << fmt::format("\n  {:.3f} s: energy {:.3f}, solve {:.3f}\n", s.seconds_build + s.seconds_solve,
                           s.seconds_build, s.seconds_solve);
}

class RunCommand final : public Command {
 public:
  std::string_view name() const override { return "run"; }
  std::string_view summary() const override {
    return "every step: change detection, then the mosaic of what is really there now";
  }

  void declare(CLI::App& app) override {
    options_.declare(app);
    app.footer(
        "Writes <output>/detect (as citymesh detect) and <output>/mosaic: mosaic.ply (per-face\n"
        "source_acq and source_face), mosaic.png and summary.json. --set mosaic.method=update-model\n"
        "runs the paper's baseline instead. Example:\n"
        "  citymesh simulate --out sim && citymesh run sim/config.toml && citymesh eval sim/out --truth sim");
  }

  void run() override {
    const Config config = options_.load();
    const ThreadLimit limit(options_.threads.value_or(config.run.threads));
    const PictureOptions pictures = options_.pictures();
    const DetectStep detect = run_detect_step(config, pictures);
    Stopwatch clock;
    const MosaicSelection selection = select(config, detect);
    MergedMesh merged = merge_selection(detect.input.meshes, detect.result.index, selection.selected);
    const double mosaic_seconds = clock.restart();
    nlohmann::json stitch_summary = nlohmann::json::object();
    if (config.mosaic.method == MosaicMethod::energy) {  // the baseline, like the paper's, is not stitched
      const StitchStats s = stitch(merged, {.reach = config.mosaic.stitch_reach * config.change.distance_threshold,
                                            .weld = kWeldInThresholds * config.change.distance_threshold});
      stitch_summary = {{"open_boundary_before_m", s.open_boundary_before},
                        {"open_boundary_after_m", s.open_boundary_after},
                        {"strips", s.strips},
                        {"triangles_added", s.triangles_added},
                        {"vertices_welded", s.vertices_welded},
                        {"rejected", s.rejected}};
      std::cout << fmt::format("stitching: {} strips, {} triangles, open boundary {:.1f} m -> {:.1f} m\n", s.strips,
                               s.triangles_added, s.open_boundary_before, s.open_boundary_after);
    }
    const double stitch_seconds = clock.restart();
    const std::filesystem::path dir = config.project.output / "mosaic";
    write_mosaic_outputs(config, detect.input, merged, selection.stats,
                         {.dir = dir,
                          .pixel_size = pictures.pixel_size,
                          .pictures = pictures.pictures,
                          .seconds = {{"read", detect.read_seconds},
                                      {"detect", detect.detect_seconds},
                                      {"mosaic", mosaic_seconds},
                                      {"stitch", stitch_seconds},
                                      {"energy", selection.stats.seconds_build},
                                      {"solve", selection.stats.seconds_solve}},
                          .stitch = stitch_summary});
    report(dir, merged, selection.stats);
  }

 private:
  PipelineOptions options_;
};

}  // namespace

std::unique_ptr<Command> make_run_command() { return std::make_unique<RunCommand>(); }

}  // namespace citymesh::app
