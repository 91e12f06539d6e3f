// SPDX-License-Identifier: MIT
// Benchmark: the tile job (change detection and mosaic of one tile with its halo) on tiles of
// a finished tile store, on one thread, so that a change to either step is measured on the
// tiles `citymesh run` processes rather than on the bench street alone, and without the noise
// of a whole run. Takes `tiles` tiles spread evenly over the store, runs each as a first-phase
// tile (no neighbour's decisions), and prints per round the seconds summed over them; the
// medians of the rounds are the figures. The selected-triangle count shows each round did the
// same work.
// Usage: tile_job_bench CONFIG [tiles (default 8)] [rounds (default 3)] [work folder (default: the config's)]
//   the work folder must hold a finished tile store (after `citymesh run`).
#include <fmt/format.h>

#include <algorithm>
#include <string>
#include <vector>

#include "bench_stats.h"
#include "citymesh/config/config.h"
#include "citymesh/core/parallel.h"
#include "citymesh/core/process_memory.h"
#include "tile_job.h"

using namespace citymesh;

namespace {

struct Round {
  double read = 0, detect = 0, mosaic = 0;
  std::uint64_t triangles = 0, selected = 0;
};

Round run_round(const Config& config, const TileStore& store, const std::vector<std::size_t>& picked) {
  Round r;
  const app::SettledSelection none;
  for (const std::size_t k : picked) {
    const app::TileResult t = app::process_tile(store, store.tiles[k].key, config, none);
    r.read += t.seconds_read;
    r.detect += t.seconds_detect;
    r.mosaic += t.seconds_mosaic;
    r.triangles += t.triangles_in_tile;
    for (const app::OwnedLabel& l : t.labels) r.selected += l.selected;
  }
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  keep_freed_memory_for_reuse();  // as the citymesh binary does
  if (argc < 2) {
    fmt::print(stderr, "usage: tile_job_bench CONFIG [tiles] [rounds] [work folder]\n");
    return 1;
  }
  try {
    Config config = load_config(argv[1]);
    if (argc > 4) config.project.work = argv[4];
    const std::size_t wanted = argc > 2 ? std::max(1, std::stoi(argv[2])) : 8;
    const int rounds = argc > 3 ? std::max(1, std::stoi(argv[3])) : 3;
    const std::optional<TileStore> store = read_tile_manifest(config.project.work / "tiles");
    if (!store || store->tiles.empty()) {
      fmt::print(stderr, "{}: no finished tile store in {} (run citymesh run first)\n", argv[1],
                 (config.project.work / "tiles").string());
      return 1;
    }
    std::vector<std::size_t> picked;
    const std::size_t n = store->tiles.size(), count = std::min(wanted, n);
    for (std::size_t i = 0; i < count; ++i) picked.push_back(i * n / count);
    const ThreadLimit one(1);
    std::vector<double> read, detect, mosaic;
    for (int r = 0; r < rounds; ++r) {
      const Round round = run_round(config, *store, picked);
      fmt::print("round {}: {} tiles, {:.2f} M triangles with halos: read {:.3f} s, detect {:.3f} s, mosaic {:.3f} s "
                 "({} selected)\n",
                 r + 1, picked.size(), double(round.triangles) / 1e6, round.read, round.detect, round.mosaic,
                 round.selected);
      read.push_back(round.read);
      detect.push_back(round.detect);
      mosaic.push_back(round.mosaic);
    }
    fmt::print("median of {} rounds, one thread: read {:.3f} s, detect {:.3f} s, mosaic {:.3f} s\n", rounds,
               bench::median(read), bench::median(detect), bench::median(mosaic));
  } catch (const std::exception& e) {
    fmt::print(stderr, "{}\n", e.what());
    return 1;
  }
  return 0;
}
