// SPDX-License-Identifier: MIT
// Benchmark: the tile job (change detection and mosaic of one tile with its halo) on tiles of
// a finished tile store, on one thread, so that a change to either step is measured on the
// tiles `citymesh run` processes rather than on the bench street alone, and without the noise
// of a whole run. Takes `tiles` tiles spread evenly over the store (or the tiles named), runs
// each as a first-phase tile (no neighbour's decisions), and prints per round the seconds
// summed over them, with the change step's stages; the medians of the rounds are the figures.
// The selected-triangle count shows each round did the same work.
// Usage: tile_job_bench CONFIG [tiles (default 8)] [rounds (default 3)] [work folder (default: the config's)]
//                      [tile names, comma-separated, as in run.json's per_tile: e.g. 13020_137218]
//   the work folder must hold a finished tile store (after `citymesh run`).
#include <fmt/format.h>

#include <algorithm>
#include <stdexcept>
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
  ChangeStats change;  ///< the change step's seconds, summed
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
    r.change.add(t.change);
    r.triangles += t.triangles_in_tile;
    for (const app::OwnedLabel& l : t.labels) r.selected += l.selected;
  }
  return r;
}

/// `wanted` tiles spread evenly over the store's list.
std::vector<std::size_t> spread_tiles(const TileStore& store, std::size_t wanted) {
  std::vector<std::size_t> picked;
  const std::size_t n = store.tiles.size(), count = std::min(wanted, n);
  for (std::size_t i = 0; i < count; ++i) picked.push_back(i * n / count);
  return picked;
}

/// The tiles named in `names` ("i_j,i_j,..."), in that order; an unknown name is an error.
std::vector<std::size_t> named_tiles(const TileStore& store, const std::string& names) {
  std::vector<std::size_t> picked;
  std::size_t from = 0;
  while (from <= names.size()) {
    const std::size_t comma = std::min(names.find(',', from), names.size());
    const std::string name = names.substr(from, comma - from);
    const auto found =
        std::find_if(store.tiles.begin(), store.tiles.end(), [&](const auto& tile) { return tile.key.name() == name; });
    if (found == store.tiles.end()) throw std::runtime_error(fmt::format("no tile {} in the tile store", name));
    picked.push_back(static_cast<std::size_t>(found - store.tiles.begin()));
    from = comma + 1;
  }
  return picked;
}

}  // namespace

int main(int argc, char** argv) {
  keep_freed_memory_for_reuse();  // as the citymesh binary does
  if (argc < 2) {
    fmt::print(stderr, "usage: tile_job_bench CONFIG [tiles] [rounds] [work folder] [tile names, comma-separated]\n");
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
    const std::vector<std::size_t> picked = argc > 5 ? named_tiles(*store, argv[5]) : spread_tiles(*store, wanted);
    const ThreadLimit one(1);
    std::vector<double> read, detect, mosaic;
    for (int r = 0; r < rounds; ++r) {
      const Round round = run_round(config, *store, picked);
      const ChangeStats& c = round.change;
      fmt::print(
          "round {}: {} tiles, {:.2f} M triangles with halos: read {:.3f} s, detect {:.3f} s (prepare {:.3f}, "
          "consistency {:.3f}, grids {:.3f}, conflicts {:.3f}, time series {:.3f}), mosaic {:.3f} s "
          "({} selected)\n",
          r + 1, picked.size(), double(round.triangles) / 1e6, round.read, round.detect, c.seconds_prepare,
          c.seconds_consistency, c.seconds_grids, c.seconds_conflicts, c.seconds_time_series, round.mosaic,
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
