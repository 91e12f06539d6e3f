// SPDX-License-Identifier: MIT
// Benchmark: the simulator. Prints Embree rays/s per core (one thread) and on all cores,
// meshing and PLY-writing throughput, for the default street and optionally a city.
// Usage: simulate_bench [--city]   (--city: 8 streets x 500 m, about 37 M triangles)
#include <fmt/format.h>

#include <chrono>
#include <cstring>
#include <filesystem>

#include "citymesh/core/process_memory.h"
#include "citymesh/core/parallel.h"
#include "citymesh/core/stopwatch.h"
#include "citymesh/sim/simulate.h"

using namespace citymesh;

namespace {

SimulationReport run(const SimulateParams& p, unsigned threads, double& wall) {
  const ThreadLimit limit(threads);
  const Stopwatch clock;
  SimulationReport r = simulate(p);
  wall = clock.seconds();
  return r;
}

void print(const char* label, unsigned threads, const SimulationReport& r, double wall) {
  const double rays = static_cast<double>(r.rays()), tris = static_cast<double>(r.triangles());
  fmt::print("simulate {} ({} thread{}): {} epochs, {:.2f} M triangles, {:.2f} s wall\n", label, threads,
             threads == 1 ? "" : "s", r.epochs.size(), tris / 1e6, wall);
  fmt::print("  scan:  {:.2f} M rays in {:.2f} s = {:.2f} M rays/s ({:.2f} M rays/s per thread; target >= 2 per core)\n",
             rays / 1e6, r.scan_seconds, rays / r.scan_seconds / 1e6, rays / r.scan_seconds / 1e6 / threads);
  fmt::print("  mesh:  {:.2f} M triangles/s\n", tris / r.mesh_seconds / 1e6);
  fmt::print("  write: {:.2f} M triangles/s written (PLY + ground truth)\n", tris / r.write_seconds / 1e6);
}

}  // namespace

int main(int argc, char** argv) {
  keep_freed_memory_for_reuse();  // as the citymesh binary does
  const bool city = argc > 1 && std::strcmp(argv[1], "--city") == 0;
  const auto out = std::filesystem::temp_directory_path() / "citymesh_simulate_bench";
  SimulateParams p;
  p.out = out;
  if (city) {
    p.streets = 8;
    p.street.length = 500.0f;
  }
  double wall = 0;
  const SimulationReport one = run(p, 1, wall);
  print(city ? "city" : "street", 1, one, wall);
  const SimulationReport all = run(p, 0, wall);
  print(city ? "city" : "street", available_threads(), all, wall);
  std::filesystem::remove_all(out);
  return static_cast<double>(one.rays()) / one.scan_seconds >= 2e6 ? 0 : 1;
}
