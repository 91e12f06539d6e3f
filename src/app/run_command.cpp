// SPDX-License-Identifier: MIT
// `citymesh run CONFIG`: every step: change detection, mosaic, output.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <optional>

#include "citymesh/config/config.h"
#include "citymesh/core/error.h"
#include "citymesh/core/log.h"
#include "citymesh/core/parallel.h"
#include "citymesh/core/process_memory.h"
#include "cluster.h"
#include "command.h"
#include "pipeline.h"
#include "tile_plan.h"
#include "tiled_run.h"

namespace citymesh::app {

namespace {

/// A budget past the machine's memory bounds nothing: the tiles in flight may then take the
/// machine into swap, or the process be killed, with no word from the run.
void warn_if_budget_past_the_machine(const Config& config) {
  const std::uint64_t machine = physical_memory_bytes();
  if (machine == 0 || config.run.memory <= machine) return;
  log::warn(
      "the memory budget ({:.1f} GiB) is more than this machine's memory ({:.1f} GiB): it bounds nothing, and "
      "the tiles in flight may take the machine into swap; give [run] memory or --memory below {:.1f} GiB",
      static_cast<double>(config.run.memory) / (1ull << 30), static_cast<double>(machine) / (1ull << 30),
      static_cast<double>(machine) / (1ull << 30));
}

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
    app.add_flag("--plan", plan_,
                 "say what the run would do with each tile (process, keep or reuse it) and how long the tiles would "
                 "take, then stop: tiles what is not tiled yet, processes nothing, writes no output");
    app.add_option("--subset", subset_,
                   "process only part i of N of the tiles (and the tiles of other parts they wait for), e.g. "
                   "--subset 2/8 in a job array; then citymesh merge CONFIG writes the outputs");
    app.footer(
        "Tiles the acquisitions into <work>/tiles ([tiling]), processes the tiles in parallel within\n"
        "the memory budget (<work>/results; finished tiles are reused when the command is run again),\n"
        "then writes <output>/detect (as citymesh detect; [output] labels), <output>/mosaic:\n"
        "mosaic.ply (per-face source_acq and source_face; [output] mosaic_ply), mosaic.png and\n"
        "summary.json, and <output>/run.json. --set mosaic.method=update-model runs the paper's\n"
        "baseline.\n"
        "Started by mpirun or srun (MPI), the ranks share the work folder: they tile the acquisitions\n"
        "and process the tiles together, rank 0 writes the outputs (docs/cluster.md). Example:\n"
        "  citymesh simulate --out sim && citymesh run sim/config.toml && citymesh eval sim/out --truth sim");
  }

  void run() override {
    // --memory is [run] memory given on the command line: same checks, same messages.
    if (memory_) options_.overrides.push_back(fmt::format("run.memory=\"{}\"", *memory_));
    std::optional<Subset> subset;
    if (subset_) subset = Subset::parse(*subset_);
    const std::unique_ptr<Cluster> cluster = join_cluster();
    if (subset && cluster->size() > 1) throw UsageError("--subset is for runs without MPI; under mpirun the ranks share the tiles");
    if (plan_ && (subset || cluster->size() > 1)) {
      throw UsageError("--plan is for a whole run in one process: leave out --subset, and run it without mpirun");
    }
    if (plan_ && force_) {
      throw UsageError(
          "--plan discards no work: leave out --force (a run with --force redoes the work its changed keys reach)");
    }
    try {
      const Config config = options_.load();
      warn_if_budget_past_the_machine(config);
      const ThreadLimit limit(options_.threads.value_or(config.run.threads));
      run_tiled(config, {.force = force_, .pictures = options_.pictures(), .subset = subset, .plan = plan_}, *cluster);
    } catch (const Error& e) {
      // The other ranks may be waiting for this one: end them all, with this error's code.
      if (cluster->size() > 1) {
        log::error("run (rank {} of {}): {} error: {}", cluster->rank(), cluster->size(), e.kind(), e.what());
        cluster->abort(static_cast<int>(e.exit_code()));
      }
      throw;
    }
  }

 private:
  PipelineOptions options_;
  std::optional<std::string> memory_;
  std::optional<std::string> subset_;
  bool force_ = false;
  bool plan_ = false;
};

}  // namespace

std::unique_ptr<Command> make_run_command() { return std::make_unique<RunCommand>(); }

}  // namespace citymesh::app
