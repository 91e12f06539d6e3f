// SPDX-License-Identifier: MIT
// `citymesh detect CONFIG`: change detection and time series over a config's acquisitions.
#include <CLI/CLI.hpp>

#include "citymesh/config/config.h"
#include "citymesh/core/parallel.h"
#include "command.h"
#include "pipeline.h"

namespace citymesh::app {

namespace {

class DetectCommand final : public Command {
 public:
  std::string_view name() const override { return "detect"; }
  std::string_view summary() const override {
    return "label every triangle consistent, conflicting or single, with first/last seen dates";
  }

  void declare(CLI::App& app) override {
    options_.declare(app);
    app.footer(
        "Writes <output>/detect/<k>_<name>.ply (per-face state, first_seen, last_seen, sustainable,\n"
        "kept), <k>_<name>.png and summary.json. Example:\n"
        "  citymesh simulate --out sim && citymesh detect sim/config.toml");
  }

  void run() override {
    const Config config = options_.load();
    const ThreadLimit limit(options_.threads.value_or(config.run.threads));
    run_detect_step(config, options_.pictures());
  }

 private:
  PipelineOptions options_;
};

}  // namespace

std::unique_ptr<Command> make_detect_command() { return std::make_unique<DetectCommand>(); }

}  // namespace citymesh::app
