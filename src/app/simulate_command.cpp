// SPDX-License-Identifier: MIT
// `citymesh simulate`: a procedural street scanned over several months, with ground truth.
#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include <chrono>
#include <iostream>

#include "citymesh/core/parallel.h"
#include "citymesh/core/stopwatch.h"
#include "citymesh/sim/simulate.h"
#include "command.h"

namespace citymesh::app {

namespace {

class SimulateCommand final : public Command {
 public:
  std::string_view name() const override { return "simulate"; }
  std::string_view summary() const override {
    return "make a street scanned at several dates, with scripted changes and per-face ground truth";
  }

  void declare(CLI::App& app) override {
    app.add_option("--out", p_.out, "output folder (created if missing)")->required();
    app.add_option("--seed", p_.street.seed, "scene and noise seed");
    app.add_option("--length", p_.street.length, "street length in metres")->check(CLI::Range(30.0, 5000.0));
    app.add_option("--width", p_.street.width, "facade-to-facade width in metres")->check(CLI::Range(14.0, 60.0));
    app.add_option("--epochs", p_.street.epochs, "number of scans (dates)")->check(CLI::Range(6, 100));
    app.add_option("--line-rate", p_.scanner.line_rate, "scan lines per second")->check(CLI::Range(1.0, 1000.0));
    app.add_option("--angular-step", p_.scanner.angular_step_deg, "degrees between pulses of a line")
        ->check(CLI::Range(0.05, 10.0));
    app.add_option("--noise", p_.scanner.range_noise, "range noise, metres (1 sigma)")->check(CLI::Range(0.0, 0.5));
    app.add_option("--tilt", p_.scanner.tilt_deg, "scan plane tilt about the vertical, degrees")
        ->check(CLI::Range(-45.0, 45.0));
    app.add_option("--scanner", scanner_, "profiler (2D scan plane) or spinning (multi-beam, one grid per turn)")
        ->check(CLI::IsMember({"profiler", "spinning"}));
    app.add_option("--rings", p_.scanner.rings, "spinning: beams")->check(CLI::Range(2, 256));
    app.add_option("--columns", p_.scanner.columns, "spinning: azimuth steps per turn")->check(CLI::Range(16, 8192));
    app.add_option("--rotation-rate", p_.scanner.rotation_rate, "spinning: turns per second")->check(CLI::Range(0.02, 50.0));
    app.add_option("--streets", p_.streets, "city mode: number of parallel streets")->check(CLI::Range(1, 1000));
    app.add_option("--street-spacing", p_.street_spacing, "city mode: metres between street centre lines")
        ->check(CLI::Range(24.0, 1000.0));
    app.add_option("--threads", threads_, "worker threads (0: all cores)");
    app.footer("Examples:\n  citymesh simulate --out sim --seed 7 --epochs 7\n"
               "  citymesh simulate --out city --streets 8 --length 500   # ~30 M triangles over 6 epochs\n"
               "Writes acq_<k>.ply, acq_<k>.truth, objects.json and config.toml under --out.");
  }

  void run() override {
    const ThreadLimit limit(threads_);
    p_.scanner.seed = p_.street.seed;
    p_.scanner.mode = scanner_ == "spinning" ? ScannerParams::Mode::spinning : ScannerParams::Mode::profiler;
    const Stopwatch clock;
    const SimulationReport r = simulate(p_);
    const double seconds = clock.seconds();
    std::cout << fmt::format("simulated {} epochs, {} objects, {} triangles in {:.2f} s ({:.2f} M rays/s)\n",
                             r.epochs.size(), r.objects, r.triangles(), seconds,
                             static_cast<double>(r.rays()) / r.scan_seconds / 1e6);
    for (const SimulatedEpoch& e : r.epochs) {
      std::cout << fmt::format("  {}: {} triangles\n", e.ply.string(), e.triangles);
    }
    std::cout << fmt::format("run it: citymesh config --check {}\n", (p_.out / "config.toml").string());
  }

 private:
  SimulateParams p_;
  unsigned threads_ = 0;
  std::string scanner_ = "profiler";
};

}  // namespace

std::unique_ptr<Command> make_simulate_command() { return std::make_unique<SimulateCommand>(); }

}  // namespace citymesh::app
