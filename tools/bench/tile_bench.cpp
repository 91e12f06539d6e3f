// SPDX-License-Identifier: MIT
// Benchmark: the tiler against just reading the same input files with the streaming PLY
// reader (the target: tiling within 2x of reading). Prints triangles/s of both, the
// ratio, the tile count and the bytes the store took. Reading, tiling one acquisition at a
// time and tiling as `run` does alternate over several rounds and the medians are compared:
// on a shared VM the same read has taken from 0.46 to 1.77 s within minutes, so a ratio of
// two single measurements says more about the host than about the tiler.
// Usage: tile_bench CONFIG [tile_size (default: the config's)] [work folder (default: temp)]
//                          [rounds (default 3)] [keep: leave the last round's store, e.g. to
//                          compare its bytes with another build's]
#include <fmt/format.h>
#include <sys/resource.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "citymesh/config/config.h"
#include "citymesh/core/parallel.h"
#include "citymesh/core/process_memory.h"
#include "citymesh/core/stopwatch.h"
#include "citymesh/tiler/tiler.h"
#include "bench_stats.h"

using namespace citymesh;

namespace {

/// Reads every acquisition front to back, as the tiler does, doing nothing with the data.
std::uint64_t read_only(const Config& config) {
  std::uint64_t triangles = 0;
  for (const AcquisitionEntry& a : config.acquisitions) {
    PlyReader reader(a.path, config.ply_read_params());
    PlyVertexChunk vertices;
    PlyFaceChunk faces;
    for (auto kind = reader.next(vertices, faces); kind != PlyReader::ChunkKind::end; kind = reader.next(vertices, faces)) {
      if (kind == PlyReader::ChunkKind::faces) triangles += faces.triangles.size();
    }
  }
  return triangles;
}

/// CPU seconds of this process so far, in all and in the kernel: next to the wall time, they
/// tell the tiler's own work from its waits on the disk and from the kernel's work of putting
/// written bytes into the page cache.
struct CpuSeconds {
  double all = 0, system = 0;
};
CpuSeconds cpu_seconds() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  const auto seconds = [](const timeval& t) { return double(t.tv_sec) + double(t.tv_usec) / 1e6; };
  return {seconds(usage.ru_utime) + seconds(usage.ru_stime), seconds(usage.ru_stime)};
}

/// Wall and CPU seconds of one measurement.
struct Timing {
  double wall = 0, cpu = 0, system = 0;
};

template <class Work>
Timing timed(Work&& work) {
  Stopwatch clock;
  const CpuSeconds before = cpu_seconds();
  work();
  const CpuSeconds after = cpu_seconds();
  return {clock.seconds(), after.all - before.all, after.system - before.system};
}

/// The median of each field over the rounds.
Timing median(const std::vector<Timing>& rounds) {
  std::vector<double> wall, cpu, system;
  for (const Timing& t : rounds) {
    wall.push_back(t.wall);
    cpu.push_back(t.cpu);
    system.push_back(t.system);
  }
  return {bench::median(std::move(wall)), bench::median(std::move(cpu)), bench::median(std::move(system))};
}

std::string wall_list(const std::vector<Timing>& rounds) {
  std::string s;
  for (const Timing& t : rounds) s += fmt::format("{}{:.2f}", s.empty() ? "" : " ", t.wall);
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  keep_freed_memory_for_reuse();  // as the citymesh binary does
  if (argc < 2) {
    fmt::print(stderr, "usage: tile_bench CONFIG [tile_size] [work folder] [rounds] [keep]\n");
    return 1;
  }
  const Config config = load_config(argv[1]);
  TilerParams params;
  params.grid = {config.tiling.tile_size, config.tiling.halo, config.tiling.origin};
  if (argc > 2) params.grid.tile_size = std::stod(argv[2]);
  params.ply = config.ply_read_params();
  params.dir = argc > 3 ? std::filesystem::path(argv[3]) : std::filesystem::temp_directory_path() / "citymesh_tile_bench";
  params.buffer_bytes = config.run.memory / 4;
  const int rounds = argc > 4 ? std::max(1, std::stoi(argv[4])) : 3;
  const bool keep = argc > 5 && std::string_view(argv[5]) == "keep";
  // As `citymesh run` tiles when the budget allows: one acquisition per thread.
  const unsigned at_once = available_threads();

  std::uint64_t triangles = 0;
  TileStore store;
  std::vector<Timing> read, tile, tile_parallel;
  std::vector<double> ratios;  // tiling as `run` against the read of the same round
  for (int r = 0; r < rounds; ++r) {
    read.push_back(timed([&] { triangles = read_only(config); }));
    // The previous round's store is deleted outside the timing: `run` tiles into a fresh work
    // folder, and deleting 0.6 GB of files is the file system's work, not the tiler's.
    std::filesystem::remove_all(params.dir);
    tile.push_back(timed([&] { store = tile_acquisitions(config.acquisition_list(), params); }));
    std::filesystem::remove_all(params.dir);
    tile_parallel.push_back(timed([&] { (void)tile_acquisitions(config.acquisition_list(), params, at_once); }));
    ratios.push_back(tile_parallel.back().wall / read.back().wall);
  }
  const Timing read_m = median(read), tile_m = median(tile), parallel_m = median(tile_parallel);
  std::sort(ratios.begin(), ratios.end());
  const auto per_second = [&](const Timing& t) { return double(triangles) / t.wall / 1e6; };
  fmt::print("input: {} acquisitions, {:.2f} M triangles, {:.0f} MB; medians of {} rounds\n", store.triangles.size(),
             double(triangles) / 1e6, double(store.stats.input_bytes) / 1e6, rounds);
  fmt::print("read only : {:7.2f} s  {:6.2f} M triangles/s (one file after another; CPU {:.2f} s; rounds: {} s)\n",
             read_m.wall, per_second(read_m), read_m.cpu, wall_list(read));
  fmt::print("tiler     : {:7.2f} s  {:6.2f} M triangles/s  ({:.2f} x the read time; one acquisition at a time; "
             "CPU {:.2f} s, kernel {:.2f} s; rounds: {} s)\n",
             tile_m.wall, per_second(tile_m), tile_m.wall / read_m.wall, tile_m.cpu, tile_m.system, wall_list(tile));
  fmt::print("tiler     : {:7.2f} s  {:6.2f} M triangles/s  ({:.2f} x the read time; {} at a time, as `run`; "
             "CPU {:.2f} s, kernel {:.2f} s; rounds: {} s; target <= 2)\n",
             parallel_m.wall, per_second(parallel_m), parallel_m.wall / read_m.wall, at_once, parallel_m.cpu,
             parallel_m.system, wall_list(tile_parallel));
  fmt::print("ratio     : {:.2f} .. {:.2f} x the read of the same round (tiling as `run`)\n", ratios.front(),
             ratios.back());
  // The kernel's share swings from run to run with the file system (on an ext4 without a
  // journal, creating files scans the inodes deleted in the last minute): user CPU alone
  // compares the tiler's own work across builds on a noisy machine.
  const double read_user = read_m.cpu - read_m.system, tile_user = tile_m.cpu - tile_m.system;
  fmt::print("user CPU  : tiler {:.2f} s against the read's {:.2f} s, {:.2f} x (one acquisition at a time, "
             "without the kernel's share)\n",
             tile_user, read_user, tile_user / read_user);
  fmt::print("tiles     : {} of {:.0f} m, halo copies {:.2f} M, empty-space copies {:.2f} M, {} blocks, {:.0f} MB "
             "written\n",
             store.tiles.size(), params.grid.tile_size, double(store.stats.halo_copies) / 1e6,
             double(store.stats.empty_space_copies) / 1e6, store.stats.blocks, double(store.stats.bytes_written) / 1e6);
  fmt::print("peak RSS  : {:.0f} MiB (buffers flushed past {:.0f} MiB)\n", double(peak_resident_bytes()) / (1 << 20),
             double(params.buffer_bytes) / (1 << 20));
  if (!keep) std::filesystem::remove_all(params.dir);
  return 0;
}
