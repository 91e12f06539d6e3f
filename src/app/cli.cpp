// SPDX-License-Identifier: MIT
// The command boundary: global options, the command registry and the one catch-all that turns
// exceptions into exit codes.
#include <CLI/CLI.hpp>
#include <new>

#include "citymesh/core/error.h"
#include "citymesh/core/interrupt.h"
#include "citymesh/core/log.h"
#include "command.h"

namespace citymesh::app {

std::vector<std::unique_ptr<Command>> make_commands() {
  std::vector<std::unique_ptr<Command>> commands;
  commands.push_back(make_info_command());
  commands.push_back(make_config_command());
  commands.push_back(make_simulate_command());
  commands.push_back(make_render_command());
  commands.push_back(make_mesh_command());
  commands.push_back(make_detect_command());
  commands.push_back(make_mosaic_command());
  commands.push_back(make_run_command());
  commands.push_back(make_merge_command());
  commands.push_back(make_eval_command());
  commands.push_back(make_check_command());
  commands.push_back(make_view_command());
  return commands;
}

namespace {

int report(std::string_view command, const Error& e) {
  log::error("{}: {} error: {}", command, e.kind(), e.what());
  return static_cast<int>(e.exit_code());
}

}  // namespace

int run_cli(int argc, char** argv) {
  install_interrupt_handlers();
  CLI::App app{"citymesh: keeps a city's 3D mesh map up to date from repeated mobile-mapping acquisitions"};
  app.name("citymesh");
  app.set_version_flag("--version", std::string(CITYMESH_VERSION));
  app.require_subcommand(1);
  app.footer("Exit codes: 0 ok, 1 usage or config, 2 input, 3 processing, 4 output, 75 interrupted.\n"
             "Run 'citymesh <command> --help' for the options of a command.\n"
             "Example: citymesh info --config configs/demo.toml");
  app.option_defaults()->always_capture_default();
  std::string level = "info";
  bool json = false;
  app.add_option("--log-level", level, "log detail on stderr: trace, debug, info, warn, error, off")
      ->check(CLI::IsMember({"trace", "debug", "info", "warn", "error", "off"}));
  app.add_flag("--log-json", json, "log one JSON object per line on stderr");

  auto commands = make_commands();
  std::vector<std::pair<CLI::App*, Command*>> subs;
  for (auto& c : commands) {
    CLI::App* sub = app.add_subcommand(std::string(c->name()), std::string(c->summary()));
    sub->option_defaults()->always_capture_default();
    c->declare(*sub);
    subs.emplace_back(sub, c.get());
  }

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    log::error("usage: {} (see 'citymesh --help')", e.what());
    return static_cast<int>(ExitCode::usage);
  }

  std::string_view name = "citymesh";
  try {
    log::configure(log::parse_level(level), json ? log::Format::json : log::Format::text);
    for (auto& [sub, command] : subs) {
      if (sub->parsed()) {
        name = command->name();
        command->run();
      }
    }
    return static_cast<int>(ExitCode::ok);
  } catch (const Error& e) {
    return report(name, e);
  } catch (const std::bad_alloc&) {
    return report(name, ProcessingError("out of memory"));
  } catch (const std::exception& e) {
    return report(name, ProcessingError(fmt::format("internal error: {}", e.what())));
  }
}

}  // namespace citymesh::app
