// SPDX-License-Identifier: MIT
// `citymesh detect CONFIG`: change detection and time series over a config's acquisitions.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <iostream>

#include "acquisitions.h"
#include "citymesh/change/detect.h"
#include "citymesh/config/config.h"
#include "citymesh/core/parallel.h"
#include "citymesh/core/stopwatch.h"
#include "command.h"
#include "detect_output.h"

namespace citymesh::app {

namespace {

class DetectCommand final : public Command {
 public:
  std::string_view name() const override { return "detect"; }
  std::string_view summary() const override {
    return "label every triangle consistent, conflicting or single, with first/last seen dates";
  }

  void declare(CLI::App& app) override {
    app.add_option("config", config_, "the run's config file")->required()->check(CLI::ExistingFile);
    app.add_option("--set", overrides_, "override a key, as section.key=value (repeatable)");
    app.add_option("--threads", threads_, "worker threads (default: [run] threads; 0: all cores)");
    app.add_option("--pixel", pixel_size_, "metres per pixel of the pictures")->check(CLI::Range(0.005, 100.0));
    app.add_flag("--no-pictures", no_pictures_, "skip the PNGs");
    app.footer(
        "Writes <output>/detect/<k>_<name>.ply (per-face state, first_seen, last_seen, sustainable,\n"
        "kept), <k>_<name>.png and summary.json. Example:\n"
        "  citymesh simulate --out sim && citymesh detect sim/config.toml");
  }

  void run() override {
    const Config config = load_config(config_, {.overrides = overrides_, .check_files = true});
    const ThreadLimit limit(threads_.value_or(config.run.threads));
    Stopwatch clock;
    const LoadedAcquisitions input = load_acquisitions(config);
    const double read_seconds = clock.restart();
    const ChangeResult result = detect_changes({input.meshes, input.dates}, config.change);
    const std::filesystem::path dir = config.project.output / "detect";
    write_detect_outputs(
        config, input, result,
        {.dir = dir, .pixel_size = pixel_size_, .pictures = !no_pictures_, .read_seconds = read_seconds});
    report(result, dir);
  }

 private:
  static void report(const ChangeResult& r, const std::filesystem::path& dir) {
    const StateCounts c = count_states(r, 0, r.index.size());
    const auto& states = c.state;
    const std::uint64_t kept = c.kept;
    const ChangeStats& s = r.stats;
    std::cout << fmt::format("{}: {} triangles: {} consistent, {} conflicting, {} single; {} kept\n", dir.string(),
                             s.triangles, states[0], states[1], states[2], kept);
    std::cout << fmt::format(
        "  {} consistent pairs; pre-filter skipped {} of {} candidates ({:.1f} %), {} exact tests\n",
        s.consistent_pairs, s.prefilter_skipped, s.conflict_candidates, 100 * s.prefilter_hit_rate(), s.exact_tests);
    std::cout << fmt::format("  {:.3f} s: consistency {:.3f}, grids {:.3f}, conflicts {:.3f}, time series {:.3f}\n",
                             s.seconds_total(), s.seconds_consistency, s.seconds_grids, s.seconds_conflicts,
                             s.seconds_time_series);
  }

  std::string config_;
  std::vector<std::string> overrides_;
  std::optional<unsigned> threads_;
  double pixel_size_ = 0.05;
  bool no_pictures_ = false;
};

}  // namespace

std::unique_ptr<Command> make_detect_command() { return std::make_unique<DetectCommand>(); }

}  // namespace citymesh::app
