// SPDX-License-Identifier: MIT
// `citymesh config`: print every key with its default, or validate a config file.
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <CLI/CLI.hpp>
#include <iostream>

#include "acquisitions.h"
#include "citymesh/config/config.h"
#include "citymesh/core/error.h"
#include "command.h"
#include "mosaic_step.h"

namespace citymesh::app {

namespace {

class ConfigCommand final : public Command {
 public:
  std::string_view name() const override { return "config"; }
  std::string_view summary() const override { return "print the default configuration or check a config file"; }

  void declare(CLI::App& app) override {
    auto* dump = app.add_flag("--dump-defaults", dump_, "print every key with its default and meaning (TOML)");
    auto* check = app.add_option("--check", check_, "validate FILE: syntax, keys, values, acquisition files");
    app.add_option("--print", print_, "validate FILE and print the effective configuration");
    app.add_option("--set", overrides_, "override a key, as section.key=value (repeatable)");
    app.add_flag("--no-file-check", no_file_check_, "do not require the acquisition files to exist");
    dump->excludes(check);
    app.footer("Examples:\n  citymesh config --dump-defaults > my.toml\n"
               "  citymesh config --check configs/example.toml --set change.distance_threshold=0.05");
  }

  void run() override {
    if (dump_) {
      std::cout << dump_default_config();
      return;
    }
    const std::string& file = !check_.empty() ? check_ : print_;
    if (file.empty()) throw UsageError("give --dump-defaults, --check FILE or --print FILE");
    const Config config = load_config(file, {.overrides = overrides_, .check_files = !no_file_check_});
    check_seam_pass(config);  // what `run` would refuse at its start
    if (!no_file_check_) {
      // What `run` checks of each file before any work: a mesh, within the CRS's area.
      for (const Acquisition& a : config.acquisition_list()) check_acquisition_file(config, a);
    }
    if (!print_.empty()) {
      std::cout << effective_config_toml(config);
      return;
    }
    std::cout << fmt::format("ok: {}: {} acquisitions, crs {} ({})\n", file, config.acquisitions.size(),
                             config.project.crs, config.crs().name());
  }

 private:
  bool dump_ = false;
  std::string check_, print_;
  std::vector<std::string> overrides_;
  bool no_file_check_ = false;
};

}  // namespace

std::unique_ptr<Command> make_config_command() { return std::make_unique<ConfigCommand>(); }

}  // namespace citymesh::app
