// SPDX-License-Identifier: MIT
// `citymesh merge CONFIG`: the outputs of a run whose tiles were processed by subsets.
#include <CLI/CLI.hpp>

#include "citymesh/config/config.h"
#include "citymesh/core/parallel.h"
#include "command.h"
#include "pipeline.h"
#include "tiled_run.h"

namespace citymesh::app {

namespace {

class MergeCommand final : public Command {
 public:
  std::string_view name() const override { return "merge"; }
  std::string_view summary() const override {
    return "after citymesh run --subset i/N for every i: assembles, stitches and writes the outputs";
  }

  void declare(CLI::App& app) override {
    options_.declare(app);
    app.footer(
        "Reads the tile store and every tile's result from the work folder (all made with this\n"
        "config), then does what the end of citymesh run does: the seam pass and every output\n"
        "(detect, mosaic, tiles, run.json), the same bytes as a run in one process. Refuses,\n"
        "naming them, when tiles have no finished result. Example (docs/cluster.md):\n"
        "  for i in 1 2 3; do citymesh run city.toml --subset $i/3; done; citymesh merge city.toml");
  }

  void run() override {
    const Config config = options_.load();
    const ThreadLimit limit(options_.threads.value_or(config.run.threads));
    merge_tiled(config, options_.pictures());
  }

 private:
  PipelineOptions options_;
};

}  // namespace

std::unique_ptr<Command> make_merge_command() { return std::make_unique<MergeCommand>(); }

}  // namespace citymesh::app
