// SPDX-License-Identifier: MIT
// `citymesh run CONFIG`: every step: change detection, mosaic, output.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <optional>

#include "citymesh/config/config.h"
#include "citymesh/core/parallel.h"
#include "command.h"
#include "pipeline.h"
#include "tiled_run.h"

namespace citymesh::app {

namespace {

class RunCommand final : public Command {
 public:
  std::string_view name() const override { return "run"; }
  std::string_view summary() const override {
    return "every step, tile by tile: change detection, mosaic, stitching; resumes unfinished work";
  }

  void declare(CLI::App& app) override {
    options_.declare(app);
    app.add_option("--memory", memory_, "memory budget for tiles in flight, e.g. 2GiB (default: [run] memory)");
    app.add_flag("--force", force_, "discard work in the work folder made with another config instead of refusing");
    app.footer(
        "Tiles the acquisitions into <work>/tiles ([tiling]), processes the tiles in parallel within\n"
        "the memory budget (<work>/results; finished tiles are reused when the command is run again),\n"
        "then writes <output>/detect (as citymesh detect; [output] labels), <output>/mosaic:\n"
        "mosaic.ply (per-face source_acq and source_face), mosaic.png and summary.json, and\n"
        "<output>/run.json. --set mosaic.method=update-model runs the paper's baseline. Example:\n"
        "  citymesh simulate --out sim && citymesh run sim/config.toml && citymesh eval sim/out --truth sim");
  }

  void run() override {
    // --memory is [run] memory given on the command line: same checks, same messages.
    if (memory_) options_.overrides.push_back(fmt::format("run.memory=\"{}\"", *memory_));
    const Config config = options_.load();
    const ThreadLimit limit(options_.threads.value_or(config.run.threads));
    run_tiled(config, {.force = force_, .pictures = options_.pictures()});
  }

 private:
  PipelineOptions options_;
  std::optional<std::string> memory_;
  bool force_ = false;
};

}  // namespace

std::unique_ptr<Command> make_run_command() { return std::make_unique<RunCommand>(); }

}  // namespace citymesh::app
