// SPDX-License-Identifier: MIT
// Benchmark: the tiler against just reading the same input files with the streaming PLY
// reader (the target: tiling within 2x of reading). Prints triangles/s of both, the
// ratio, the tile count and the bytes the store took.
// Usage: tile_bench CONFIG [tile_size (default: the config's)] [work folder (default: temp)]
#include <fmt/format.h>
#include <sys/resource.h>

#include <cstdlib>
#include <filesystem>
#include <string>
#include <utility>

#include "citymesh/config/config.h"
#include "citymesh/core/parallel.h"
#include "citymesh/core/process_memory.h"
#include "citymesh/core/stopwatch.h"
#include "citymesh/tiler/tiler.h"

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

/// CPU seconds (user and system) of this process so far: next to the wall time, it tells
/// the tiler's own work from its waits on the disk.
double cpu_seconds() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  const auto seconds = [](const timeval& t) { return double(t.tv_sec) + double(t.tv_usec) / 1e6; };
  return seconds(usage.ru_utime) + seconds(usage.ru_stime);
}

}  // namespace

int main(int argc, char** argv) {
  keep_freed_memory_for_reuse();  // as the citymesh binary does
  if (argc < 2) {
    fmt::print(stderr, "usage: tile_bench CONFIG [tile_size] [work folder]\n");
    return 1;
  }
  const Config config = load_config(argv[1]);
  TilerParams params;
  params.grid = {config.tiling.tile_size, config.tiling.halo, config.tiling.origin};
  if (argc > 2) params.grid.tile_size = std::stod(argv[2]);
  params.ply = config.ply_read_params();
  params.dir = argc > 3 ? std::filesystem::path(argv[3]) : std::filesystem::temp_directory_path() / "citymesh_tile_bench";
  params.buffer_bytes = config.run.memory / 4;

  Stopwatch clock;
  double cpu = cpu_seconds();
  const auto cpu_since = [&cpu] {
    const double before = std::exchange(cpu, cpu_seconds());
    return cpu - before;
  };
  const std::uint64_t triangles = read_only(config);
  const double read = clock.restart(), read_cpu = cpu_since();
  const TileStore store = tile_acquisitions(config.acquisition_list(), params);
  const double tile = clock.restart(), tile_cpu = cpu_since();
  // As `citymesh run` tiles when the budget allows: one acquisition per thread.
  const unsigned at_once = available_threads();
  (void)tile_acquisitions(config.acquisition_list(), params, at_once);
  const double tile_parallel = clock.restart(), tile_parallel_cpu = cpu_since();
  fmt::print("input: {} acquisitions, {:.2f} M triangles, {:.0f} MB\n", store.triangles.size(), double(triangles) / 1e6,
             double(store.stats.input_bytes) / 1e6);
  fmt::print("read only : {:7.2f} s  {:6.2f} M triangles/s (one file after another; CPU {:.2f} s)\n", read,
             double(triangles) / read / 1e6, read_cpu);
  fmt::print("tiler     : {:7.2f} s  {:6.2f} M triangles/s  ({:.2f} x the read time; one acquisition at a time; "
             "CPU {:.2f} s)\n",
             tile, double(triangles) / tile / 1e6, tile / read, tile_cpu);
  fmt::print("tiler     : {:7.2f} s  {:6.2f} M triangles/s  ({:.2f} x the read time; {} at a time, as `run`; "
             "CPU {:.2f} s; target <= 2)\n",
             tile_parallel, double(triangles) / tile_parallel / 1e6, tile_parallel / read, at_once, tile_parallel_cpu);
  fmt::print("tiles     : {} of {:.0f} m, halo copies {:.2f} M, empty-space copies {:.2f} M, {} blocks, {:.0f} MB "
             "written\n",
             store.tiles.size(), params.grid.tile_size, double(store.stats.halo_copies) / 1e6,
             double(store.stats.empty_space_copies) / 1e6, store.stats.blocks, double(store.stats.bytes_written) / 1e6);
  fmt::print("peak RSS  : {:.0f} MiB (buffers flushed past {:.0f} MiB)\n", double(peak_resident_bytes()) / (1 << 20),
             double(params.buffer_bytes) / (1 << 20));
  std::filesystem::remove_all(params.dir);
  return 0;
}
