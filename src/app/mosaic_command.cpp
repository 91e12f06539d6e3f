// SPDX-License-Identifier: MIT
// `citymesh mosaic CONFIG`: the mosaic step alone, on the result of an earlier `detect`.
#include <CLI/CLI.hpp>

#include "citymesh/config/config.h"
#include "citymesh/core/parallel.h"
#include "citymesh/core/stopwatch.h"
#include "command.h"
#include "leftovers.h"
#include "mosaic_step.h"
#include "pipeline.h"

namespace citymesh::app {

namespace {

class MosaicCommand final : public Command {
 public:
  std::string_view name() const override { return "mosaic"; }
  std::string_view summary() const override { return "after detect: the mosaic of what is really there now"; }

  void declare(CLI::App& app) override {
    options_.declare(app);
    app.footer(
        "Reads <output>/detect (written by citymesh detect with the same acquisitions) and writes\n"
        "<output>/mosaic like citymesh run. Change [mosaic] keys freely between runs; change\n"
        "[change] keys and detect again. Example:\n"
        "  citymesh detect sim/config.toml && citymesh mosaic sim/config.toml --set mosaic.quality=area");
  }

  void run() override {
    const Config config = options_.load();
    const ThreadLimit limit(options_.threads.value_or(config.run.threads));
    Stopwatch clock;
    remove_leftovers_of_ended_runs(config);
    const LoadedAcquisitions input = load_acquisitions(config);
    const ChangeResult change = read_detect_result(config.project.output / "detect", config, input);
    run_mosaic_step(config, input, change, options_.pictures(), {{"read", clock.seconds()}});
  }

 private:
  PipelineOptions options_;
};

}  // namespace

std::unique_ptr<Command> make_mosaic_command() { return std::make_unique<MosaicCommand>(); }

}  // namespace citymesh::app
