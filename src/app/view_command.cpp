// SPDX-License-Identifier: MIT
// `citymesh view OUTPUT`: serves a run's tileset and the viewer pages (three.js, CesiumJS) on localhost.
// The only source that includes cpp-httplib.
#include <fmt/format.h>
#include <httplib.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <chrono>
#include <iostream>
#include <thread>

#include "citymesh/core/error.h"
#include "citymesh/core/interrupt.h"
#include "citymesh/core/log.h"
#include "command.h"
#include "tileset_output.h"

namespace citymesh::app {

namespace {

/// Where tools/setup installs the viewer page and its npm packages.
constexpr const char* kDefaultViewerDir = CITYMESH_SOURCE_DIR "/tools/web";

void require_viewer(const std::filesystem::path& viewer) {
  for (const char* needed : {"viewer/index.html", "node_modules/three/build/three.module.js",
                             "node_modules/3d-tiles-renderer/build/index.js"}) {
    if (!std::filesystem::is_regular_file(viewer / needed)) {
      throw UsageError(fmt::format("{}: missing; install the viewer's packages with tools/setup "
                                   "(npm ci in {})", (viewer / needed).string(), viewer.string()));
    }
  }
}

class ViewCommand final : public Command {
 public:
  std::string_view name() const override { return "view"; }
  std::string_view summary() const override { return "serve a tileset and the web viewer on localhost"; }

  void declare(CLI::App& app) override {
    app.add_option("output", output_, "a run's output folder (or a folder holding tileset.json)")->required();
    app.add_option("--port", port_, "TCP port on 127.0.0.1 (0: any free port)")->check(CLI::Range(0, 65535));
    app.add_option("--viewer", viewer_, "folder of the viewer page and its node_modules");
    app.footer(
        "Listens on 127.0.0.1 only, prints the address to open, and serves until Ctrl-C. The three.js\n"
        "viewer is at /, the same tileset in CesiumJS at /cesium.html. Both colour triangles by\n"
        "acquisition (?color=date: by date, ?color=none: grey; ?error=2 for finer tiles) and name\n"
        "the acquisition of a clicked triangle. Example:\n"
        "  citymesh run sim/config.toml && citymesh view sim/out   # then open http://127.0.0.1:8080/");
  }

  void run() override {
    const std::filesystem::path tileset = find_tileset(output_), viewer = viewer_;
    const std::filesystem::path tiles = tileset.has_parent_path() ? tileset.parent_path() : ".";
    require_viewer(viewer);
    httplib::Server server;
    server.set_file_extension_and_mimetype_mapping("glb", "model/gltf-binary");
    server.set_file_extension_and_mimetype_mapping("wasm", "application/wasm");
    server.set_file_extension_and_mimetype_mapping("mjs", "text/javascript");
    server.set_default_headers({{"Cache-Control", "no-store"}});
    server.set_mount_point("/tiles", tiles.string());
    server.set_mount_point("/node_modules", (viewer / "node_modules").string());
    server.set_mount_point("/", (viewer / "viewer").string());
    const int port = port_ == 0 ? server.bind_to_any_port("127.0.0.1") : (server.bind_to_port("127.0.0.1", port_) ? port_ : -1);
    if (port < 0) throw UsageError(fmt::format("cannot listen on 127.0.0.1:{} (in use?)", port_));
    std::cout << fmt::format("serving {} on http://127.0.0.1:{}/ (Ctrl-C stops)", tiles.string(), port) << std::endl;
    if (std::filesystem::is_regular_file(viewer / "node_modules/cesium/Build/Cesium/Cesium.js")) {
      std::cout << fmt::format("the same tileset in CesiumJS: http://127.0.0.1:{}/cesium.html", port) << std::endl;
    }
    std::atomic<bool> listening = true;
    std::thread listener([&] {
      server.listen_after_bind();
      listening = false;
    });
    while (!interrupt_requested() && listening) std::this_thread::sleep_for(std::chrono::milliseconds(100));
    server.stop();
    listener.join();
    clear_interrupt();  // Ctrl-C is how a user ends the viewer: not a failure
    log::info("viewer stopped");
  }

 private:
  std::string output_;
  std::string viewer_ = kDefaultViewerDir;
  int port_ = 8080;
};

}  // namespace

std::unique_ptr<Command> make_view_command() { return std::make_unique<ViewCommand>(); }

}  // namespace citymesh::app
