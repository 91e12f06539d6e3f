// SPDX-License-Identifier: MIT
// A citymesh sub-command: declares its options on a CLI11 sub-app, then runs.
#pragma once

#include <memory>
#include <string_view>
#include <vector>

namespace CLI {
class App;
}

namespace citymesh::app {

class Command {
 public:
  virtual ~Command() = default;
  [[nodiscard]] virtual std::string_view name() const = 0;
  [[nodiscard]] virtual std::string_view summary() const = 0;
  /// Declares every option with its default, range and an example in the footer.
  virtual void declare(CLI::App& app) = 0;
  /// Does the work; failures are thrown as citymesh::Error subclasses.
  virtual void run() = 0;
};

std::unique_ptr<Command> make_info_command();
std::unique_ptr<Command> make_config_command();
std::unique_ptr<Command> make_simulate_command();
std::unique_ptr<Command> make_render_command();
std::unique_ptr<Command> make_mesh_command();
std::unique_ptr<Command> make_detect_command();
std::unique_ptr<Command> make_eval_command();
std::unique_ptr<Command> make_run_command();
std::unique_ptr<Command> make_mosaic_command();
std::unique_ptr<Command> make_merge_command();
std::unique_ptr<Command> make_check_command();
std::unique_ptr<Command> make_view_command();

/// Every command, in the order `citymesh --help` lists them. New commands register here.
std::vector<std::unique_ptr<Command>> make_commands();

/// Parses the command line, runs the chosen command and maps failures to exit codes.
int run_cli(int argc, char** argv);

}  // namespace citymesh::app
