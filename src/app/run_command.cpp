// SPDX-License-Identifier: MIT
// `citymesh run CONFIG`: every step: change detection, mosaic, output.
#include <CLI/CLI.hpp>

#include "citymesh/config/config.h"
#include "citymesh/core/parallel.h"
#include "command.h"
#include "mosaic_step.h"
#include "pipeline.h"

namespace citymesh::app {

namespace {

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
    run_mosaic_step(config, detect.input, detect.result, pictures,
                    {{"read", detect.read_seconds}, {"detect", detect.detect_seconds}});
  }

 private:
  PipelineOptions options_;
};

}  // namespace

std::unique_ptr<Command> make_run_command() { return std::make_unique<RunCommand>(); }

}  // namespace citymesh::app
