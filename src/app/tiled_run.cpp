// SPDX-License-Identifier: MIT
#include "tiled_run.h"

#include <fmt/format.h>

#include <algorithm>
#include <condition_variable>
#include <iostream>
#include <mutex>
#include <nlohmann/json.hpp>

#include "citymesh/core/atomic_file.h"
#include "citymesh/core/error.h"
#include "citymesh/core/interrupt.h"
#include "citymesh/core/log.h"
#include "citymesh/core/parallel.h"
#include "citymesh/core/process_memory.h"
#include "citymesh/core/stopwatch.h"
#include "citymesh/tiler/tiler.h"
#include "detect_output.h"
#include "mosaic_output.h"
#include "mosaic_step.h"
#include "run_state.h"
#include "tile_assembly.h"
#include "tile_job.h"
#include "tileset_output.h"

namespace citymesh::app {

namespace {

/// Estimated peak bytes of a tile in flight per triangle it holds (all roles): meshes, change
/// step (~180 B) and mosaic, measured on the default street (docs/tiling.md).
constexpr std::uint64_t kBytesPerTileTriangle = 900;

/// Bounds the estimated bytes of the tiles in flight. A tile larger than the whole budget
/// still runs, alone.
class MemoryGate {
 public:
  explicit MemoryGate(std::uint64_t budget) : budget_(budget) {}
  void acquire(std::uint64_t bytes) {
    std::unique_lock lock(mutex_);
    freed_.wait(lock, [&] { return in_use_ == 0 || in_use_ + bytes <= budget_; });
    in_use_ += bytes;
  }
  void release(std::uint64_t bytes) {
    {
      const std::lock_guard lock(mutex_);
      in_use_ -= bytes;
    }
    freed_.notify_all();
  }

 private:
  std::mutex mutex_;
  std::condition_variable freed_;
  std::uint64_t budget_, in_use_ = 0;
};

/// Progress lines on stderr: tiles done, input triangles per second, ETA, memory.
class Progress {
 public:
  Progress(std::size_t tiles, std::uint64_t triangles) : tiles_(tiles), triangles_(triangles) {}
  void done(std::uint64_t owned) {
    const std::lock_guard lock(mutex_);
    ++done_;
    triangles_done_ += owned;
    if (done_ < tiles_ && since_line_.seconds() < 1.0) return;
    since_line_.restart();
    const double rate = static_cast<double>(triangles_done_) / std::max(clock_.seconds(), 1e-9);
    const double eta = rate > 0 ? static_cast<double>(triangles_ - triangles_done_) / rate : 0.0;
    log::info("tiles {}/{}, {:.2f} M triangles/s, ETA {:.0f} s, memory {:.0f} MiB", done_, tiles_, rate / 1e6, eta,
              static_cast<double>(resident_bytes()) / (1 << 20));
  }

 private:
  std::mutex mutex_;
  std::size_t tiles_, done_ = 0;
  std::uint64_t triangles_, triangles_done_ = 0;
  Stopwatch clock_, since_line_;
};

std::filesystem::path result_path(const Config& config, TileKey key) {
  return config.project.work / "results" / (key.name() + ".bin");
}

TileStore tile_or_reuse(const Config& config, std::uint64_t tiling_fingerprint) {
  const std::filesystem::path dir = config.project.work / "tiles";
  const std::string wanted = fmt::format("{:016x}", tiling_fingerprint);
  if (std::optional<TileStore> store = read_tile_manifest(dir); store && store->fingerprint == wanted) {
    log::info("{}: reusing the tile store ({} tiles)", dir.string(), store->tiles.size());
    return *store;
  }
  TilerParams params;
  params.grid = {config.tiling.tile_size, config.tiling.halo, config.tiling.origin};
  params.ply = config.ply_read_params();
  params.dir = dir;
  params.buffer_bytes = std::max<std::uint64_t>(config.run.memory / 4, 16ull << 20);
  TileStore store = tile_acquisitions(config.acquisition_list(), params);
  store.fingerprint = wanted;
  write_tile_manifest(store);
  log::info("tiled {} acquisitions into {} tiles in {:.2f} s", store.triangles.size(), store.tiles.size(),
            store.stats.seconds);
  return store;
}

struct TileTimes {
  std::vector<nlohmann::json> per_tile;
  std::size_t reused = 0;
};

/// The labels of the neighbours of `key` processed in earlier phases, sorted.
std::vector<OwnedLabel> settled_labels(const Config& config, const TileStore& store, TileKey key,
                                       std::uint64_t fingerprint) {
  std::vector<OwnedLabel> labels;
  for (std::int32_t di = -1; di <= 1; ++di) {
    for (std::int32_t dj = -1; dj <= 1; ++dj) {
      const TileKey n{key.i + di, key.j + dj};
      if (tile_phase(n) >= tile_phase(key)) continue;
      const auto it = std::lower_bound(store.tiles.begin(), store.tiles.end(), n,
                                       [](const TileContents& t, TileKey k) { return t.key < k; });
      if (it == store.tiles.end() || it->key != n) continue;
      std::optional<TileResult> r = read_tile_result(result_path(config, n), fingerprint, store);
      if (!r) throw ProcessingError(fmt::format("{}: missing, needed by tile {}", result_path(config, n).string(), key.name()));
      labels.insert(labels.end(), r->labels.begin(), r->labels.end());
    }
  }
  std::sort(labels.begin(), labels.end(), by_triangle);
  return labels;
}

/// Processes every tile without a finished result, phase by phase (tiles of one phase never
/// touch), largest first within a phase, within the memory budget.
TileTimes process_tiles(const Config& config, const TileStore& store, std::uint64_t fingerprint) {
  std::uint64_t input = 0;
  for (const TileContents& t : store.tiles) input += t.owned();
  TileTimes times;
  times.per_tile.resize(store.tiles.size());
  MemoryGate gate(config.run.memory);
  Progress progress(store.tiles.size(), input);
  std::mutex mutex;
  for (int phase = 0; phase < kTilePhases; ++phase) {
    std::vector<std::size_t> order;
    for (std::size_t k = 0; k < store.tiles.size(); ++k) {
      if (tile_phase(store.tiles[k].key) == phase) order.push_back(k);
    }
    std::stable_sort(order.begin(), order.end(),
                     [&](std::size_t a, std::size_t b) { return store.tiles[a].total() > store.tiles[b].total(); });
    parallel_for_blocks(order.size(), 1, [&](std::size_t begin, std::size_t end) {
      for (std::size_t n = begin; n < end; ++n) {
        const TileContents& tile = store.tiles[order[n]];
        const std::filesystem::path file = result_path(config, tile.key);
        nlohmann::json entry{{"tile", tile.key.name()}, {"owned", tile.owned()}, {"triangles", tile.total()}};
        if (read_tile_result(file, fingerprint, store)) {
          entry["reused"] = true;
          const std::lock_guard lock(mutex);
          ++times.reused;
        } else {
          throw_if_interrupted("tile processing");
          const std::uint64_t estimate = tile.total() * kBytesPerTileTriangle;
          gate.acquire(estimate);
          try {
            const TileResult r =
                process_tile(store, tile.key, config, settled_labels(config, store, tile.key, fingerprint));
            write_tile_result(file, r, fingerprint);
            entry["seconds"] = {{"read", r.seconds_read}, {"detect", r.seconds_detect}, {"mosaic", r.seconds_mosaic}};
          } catch (...) {
            gate.release(estimate);
            throw;
          }
          gate.release(estimate);
        }
        times.per_tile[order[n]] = std::move(entry);
        progress.done(tile.owned());
      }
    });
  }
  return times;
}

LoadedAcquisitions describe_acquisitions(const Config& config) {
  LoadedAcquisitions d;
  d.acquisitions = config.acquisition_list();
  for (const Acquisition& a : d.acquisitions) d.dates.push_back(a.date);
  return d;
}

/// The change step's outputs from the tiles' labels; the acquisitions are read again, one
/// PLY each, to carry the labels.
void write_labels(const Config& config, const TileAssembly& assembly, const PictureOptions& pictures) {
  Stopwatch clock;
  LoadedAcquisitions input = load_acquisitions(config);
  const ChangeResult change = assembly.change();
  for (std::size_t k = 0; k < input.meshes.size(); ++k) {
    if (input.meshes[k].triangle_count() != change.index.offsets[k + 1] - change.index.offsets[k]) {
      throw InputError(fmt::format("{}: {} triangles now, {} when it was tiled (run with --force)",
                                   input.acquisitions[k].path.string(), input.meshes[k].triangle_count(),
                                   change.index.offsets[k + 1] - change.index.offsets[k]));
    }
  }
  write_detect_outputs(config, input, change,
                       {.dir = config.project.output / "detect",
                        .pixel_size = pictures.pixel_size,
                        .pictures = pictures.pictures,
                        .read_seconds = clock.seconds()});
}

}  // namespace

void run_tiled(const Config& config, const TiledRunOptions& options) {
  Stopwatch total, clock;
  const auto keys = result_keys(config);
  check_run_config(config.project.work, keys, options.force);
  const std::uint64_t result_fingerprint = fingerprint(keys, false);
  const TileStore store = tile_or_reuse(config, fingerprint(keys, true));
  nlohmann::json seconds{{"tiling", clock.restart()}};
  std::filesystem::create_directories(config.project.work / "results");
  TileTimes times = process_tiles(config, store, result_fingerprint);
  seconds["tiles"] = clock.restart();

  TileAssembly assembly(store, config.output.labels);
  for (const TileContents& tile : store.tiles) {
    std::optional<TileResult> r = read_tile_result(result_path(config, tile.key), result_fingerprint, store);
    if (!r) throw ProcessingError(fmt::format("{}: the tile result vanished", result_path(config, tile.key).string()));
    assembly.add(std::move(*r));
  }
  MergedMesh merged = assembly.merged();
  const std::uint64_t selected = merged.mesh.triangle_count();
  seconds["assembly"] = clock.restart();
  if (config.output.labels) write_labels(config, assembly, options.pictures);
  seconds["labels"] = clock.restart();
  // The seam pass: stitching runs on the assembled mesh, so seams between tiles are joined
  // like seams inside a tile.
  const nlohmann::json stitched = config.mosaic.method == MosaicMethod::energy
                                      ? stitch_and_report(config, merged)
                                      : nlohmann::json::object();
  seconds["stitch"] = clock.restart();
  MosaicStats stats;
  stats.candidates = assembly.candidates();
  stats.selected = selected;
  write_mosaic_outputs(config, describe_acquisitions(config), merged, stats,
                       {.dir = config.project.output / "mosaic",
                        .pixel_size = options.pictures.pixel_size,
                        .pictures = options.pictures.pictures,
                        .seconds = seconds,
                        .stitch = stitched});
  seconds["outputs"] = clock.restart();
  const nlohmann::json exported = write_tileset_outputs(config, merged);
  seconds["export"] = clock.restart();

  const double wall = total.seconds();
  nlohmann::json report;
  report["tiles"] = store.tiles.size();
  report["reused_tiles"] = times.reused;
  report["input_triangles"] = assembly.owned();
  report["output_triangles"] = merged.mesh.triangle_count();
  report["threads"] = available_threads();
  report["memory_budget"] = format_byte_size(config.run.memory);
  report["peak_rss_bytes"] = peak_resident_bytes();
  report["seconds"] = seconds;
  report["seconds"]["total"] = wall;
  report["triangles_per_second"] = static_cast<double>(assembly.owned()) / std::max(wall, 1e-9);
  report["tiling"] = {{"halo_copies", store.stats.halo_copies},
                      {"empty_space_copies", store.stats.empty_space_copies},
                      {"bytes_written", store.stats.bytes_written}};
  report["export"] = exported;
  report["per_tile"] = times.per_tile;
  write_file_atomically(config.project.output / "run.json", report.dump(1) + "\n");
  std::cout << fmt::format("run: {} tiles ({} reused), {} input triangles -> {} output triangles in {:.2f} s "
                           "({:.2f} M triangles/s), peak memory {:.0f} MiB\n",
                           store.tiles.size(), times.reused, assembly.owned(), merged.mesh.triangle_count(),
                           wall, static_cast<double>(assembly.owned()) / std::max(wall, 1e-9) / 1e6,
                           static_cast<double>(peak_resident_bytes()) / (1 << 20));
}

}  // namespace citymesh::app
