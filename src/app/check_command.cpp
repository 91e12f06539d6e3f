// SPDX-License-Identifier: MIT
// `citymesh check OUTPUT`: the structural checks of a written 3D Tiles tileset, for users.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <iostream>

#include "citymesh/core/error.h"
#include "citymesh/tiles3d/check.h"
#include "command.h"
#include "tileset_output.h"

namespace citymesh::app {

namespace {

class CheckCommand final : public Command {
 public:
  std::string_view name() const override { return "check"; }
  std::string_view summary() const override { return "check a written 3D Tiles tileset (structure, glb, Draco)"; }

  void declare(CLI::App& app) override {
    app.add_option("output", output_, "a run's output folder, a tileset folder or a tileset.json")->required();
    app.add_option("--max-json-kb", max_json_kb_, "largest allowed tileset JSON file (kB)")->check(CLI::Range(1, 1 << 20));
    app.footer(
        "Decodes every glb and checks it against its tile (counts, bounds, feature ids); exit code 2 and\n"
        "one line per problem when something is wrong. Example:\n"
        "  citymesh run sim/config.toml && citymesh check sim/out");
  }

  void run() override {
    const std::filesystem::path tileset = find_tileset(output_);
    const TilesetCheckReport r = check_tileset(tileset, {.max_json_bytes = max_json_kb_ * 1024, .box_tolerance = 0.01});
    std::cout << fmt::format("{}: {} tiles ({} levels), {} glb ({:.1f} MiB), {} tileset files ({:.1f} kB), "
                             "{} triangles in the leaves, {} in all contents\n",
                             tileset.string(), r.tiles, r.levels, r.glb_files,
                             static_cast<double>(r.glb_bytes) / (1 << 20), r.json_files,
                             static_cast<double>(r.json_bytes) / 1024, r.leaf_triangles, r.triangles);
    std::cout << fmt::format("  cracks between levels of detail: {:.2f} m in {} tiles, against {:.1f} m of seams "
                             "between leaves\n",
                             r.crack_length, r.cracked_tiles.size(), r.seam_length);
    constexpr std::size_t kListed = 5;
    for (std::size_t i = 0; i < std::min(kListed, r.cracked_tiles.size()); ++i) {
      std::cout << fmt::format("    {}: {:.2f} m\n", r.cracked_tiles[i].first, r.cracked_tiles[i].second);
    }
    for (const std::string& e : r.errors) std::cout << "  problem: " << e << "\n";
    if (!r.ok()) throw InputError(fmt::format("{}: {} problems", tileset.string(), r.errors.size()));
    std::cout << "ok\n";
  }

 private:
  std::string output_;
  std::uint64_t max_json_kb_ = 512;
};

}  // namespace

std::unique_ptr<Command> make_check_command() { return std::make_unique<CheckCommand>(); }

}  // namespace citymesh::app
