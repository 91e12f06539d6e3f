// SPDX-License-Identifier: MIT
// The tile stage: every tile processed once its earlier-phase neighbours are done, on the
// worker threads of every rank, within each rank's memory budget.
#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <thread>

#include "citymesh/core/error.h"
#include "citymesh/core/interrupt.h"
#include "citymesh/core/log.h"
#include "citymesh/core/parallel.h"
#include "citymesh/core/process_memory.h"
#include "citymesh/core/stopwatch.h"
#include "citymesh/core/time.h"
#include "run_stages.h"
#include "tile_job.h"

namespace citymesh::app {

namespace {

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

/// Progress lines on stderr: tiles done of those to process (and how many are reused),
/// input triangles per second, ETA, memory. Reused tiles count neither in the total nor in
/// the ETA: a resumed or appended run would otherwise show an ETA for work it does not do.
class Progress {
 public:
  Progress(std::size_t tiles, std::uint64_t triangles, std::size_t reused)
      : tiles_(tiles), reused_(reused), triangles_(triangles) {}
  /// A tile to process found still right (keep_if_still_right): reused after all. Called
  /// under the work channel's lock.
  void kept(std::uint64_t owned) {
    --tiles_;
    ++reused_;
    triangles_ -= std::min(triangles_, owned);
    say_if_due();
  }
  /// Called under the work channel's lock.
  void done(std::uint64_t owned) {
    ++done_;
    triangles_done_ += owned;
    say_if_due();
  }

 private:
  /// A line a second, and one when the last tile is done.
  void say_if_due() {
    if (done_ < tiles_ && since_line_.seconds() < 1.0) return;
    since_line_.restart();
    const double rate = static_cast<double>(triangles_done_) / std::max(clock_.seconds(), 1e-9);
    const double eta =
        rate > 0 && triangles_ > triangles_done_ ? static_cast<double>(triangles_ - triangles_done_) / rate : 0.0;
    log::info("tiles {}/{}{}, {:.2f} M triangles/s, ETA {:.0f} s, memory {:.0f} MiB", done_, tiles_,
              reused_ > 0 ? fmt::format(" ({} reused)", reused_) : std::string(), rate / 1e6, eta,
              static_cast<double>(resident_bytes()) / (1 << 20));
  }

  std::size_t tiles_, reused_, done_ = 0;
  std::uint64_t triangles_, triangles_done_ = 0;
  Stopwatch clock_, since_line_;
};

/// A dependency's labels. On a shared filesystem a file another machine just renamed into
/// place may take a moment to appear: look again for a few seconds before giving up.
std::vector<OwnedLabel> dependency_labels(const Config& config, const TileStore& store, TileKey key, TileKey needed_by,
                                          std::uint64_t digest) {
  const std::filesystem::path file = result_path(config, key);
  for (int attempt = 0;; ++attempt) {
    if (std::optional<std::vector<OwnedLabel>> labels = read_tile_labels(file, digest, store)) {
      return std::move(*labels);
    }
    if (attempt == 20)
      throw ProcessingError(fmt::format("{}: missing, needed by tile {}", file.string(), needed_by.name()));
    std::this_thread::sleep_for(std::chrono::milliseconds(250));
  }
}

/// The decisions of the tiles `k` waits for.
SettledSelection settled_selection(const Config& config, const TileStore& store, std::size_t k,
                                   std::span<const std::uint64_t> digests) {
  SettledSelection settled;
  for (const std::size_t d : tile_dependencies(store, k)) {
    settled.add(dependency_labels(config, store, store.tiles[d].key, store.tiles[k].key, digests[d]));
  }
  return settled;
}

/// Whether another rank kept tile `key` (it reported the tile done like one it processed; the
/// result's header says which). False when the result cannot be read yet, as may happen for a
/// moment on a shared file system: the stage's report is mended at its end.
bool kept_elsewhere(const Config& config, TileKey key) {
  const std::optional<ResultOrigin> origin = tile_result_origin(result_path(config, key));
  return origin && origin->kept;
}

/// Tiles another rank kept and the progress counted as processed: their results say which.
void count_kept_elsewhere(const Config& config, const TileStore& store, const std::vector<std::size_t>& tiles,
                          TileStageReport& report) {
  for (const std::size_t k : tiles) {
    if (report.processed[k] == 0 || !kept_elsewhere(config, store.tiles[k].key)) continue;
    report.processed[k] = 0;
    --report.count;
    ++report.kept;
  }
}

/// Whether tile `key` has a finished result made under `digest`: complete (the checksum
/// covers the whole file); it is decoded once, by the final pass.
bool has_finished_result(const Config& config, const TileStore& store, TileKey key, std::uint64_t digest) {
  return tile_result_is_finished(result_path(config, key), digest, store);
}

/// Per item of `tiles` (positions in store.tiles): 1 when its tile has a finished result.
std::vector<std::uint8_t> finished_items(const Config& config, const TileStore& store,
                                         std::span<const std::uint64_t> digests,
                                         const std::vector<std::size_t>& tiles) {
  std::vector<std::uint8_t> done;
  for (const std::size_t k : tiles)
    done.push_back(has_finished_result(config, store, store.tiles[k].key, digests[k]) ? 1 : 0);
  return done;
}

/// The schedule of `tiles` (positions in `tiles`), with the items `done` finished already.
WorkSchedule tile_schedule(const TileStore& store, const std::vector<std::size_t>& tiles,
                           std::span<const std::uint8_t> theirs, std::vector<std::uint8_t> done) {
  std::vector<std::vector<std::size_t>> after;
  for (const std::size_t k : tiles) {
    std::vector<std::size_t> positions;
    for (const std::size_t d : tile_dependencies(store, k)) {
      const auto it = std::lower_bound(tiles.begin(), tiles.end(), d);
      if (it == tiles.end() || *it != d) {
        throw ProcessingError(fmt::format("tile {} waits for tile {}, which is not planned", store.tiles[k].key.name(),
                                          store.tiles[d].key.name()));
      }
      positions.push_back(static_cast<std::size_t>(it - tiles.begin()));
    }
    after.push_back(std::move(positions));
  }
  return WorkSchedule(tile_priorities(store, tiles, theirs), after, done);
}

/// Says once which tiles the budget cannot hold, and what to change.
void warn_tiles_over_budget(const Config& config, const TileStore& store, const std::vector<std::size_t>& tiles) {
  const std::vector<std::size_t> over = tiles_over_budget(store, tiles, config.run.memory);
  if (over.empty()) return;
  const TileContents& largest = store.tiles[over.front()];
  log::warn(
      "{} of {} tiles are estimated above the memory budget of {} (largest: tile {}, {} triangles with its "
      "halo, ~{} MiB); each runs alone, its mosaic solving with the least memory, and may pass the budget: use a "
      "smaller [tiling] tile_size or a larger --memory",
      over.size(), tiles.size(), format_byte_size(config.run.memory), largest.key.name(), largest.total(),
      tile_memory_estimate(largest) >> 20);
}

/// Says when the tiles took this process past the budget: the estimate (bytes per triangle
/// held) is right for one sheet per pass, not for inputs whose surfaces are many layers deep,
/// whose pairs of overlapping triangles it does not count.
void warn_if_past_budget(const Config& config) {
  const std::uint64_t peak = peak_resident_bytes();
  if (peak <= config.run.memory) return;
  log::warn(
      "the tiles took this process to {} MiB, past the memory budget of {}: their surfaces are more layers "
      "deep than the estimate allows for (many passes, or overlapping turns of a spinning scanner in one "
      "pass); use a smaller [tiling] tile_size or a larger --memory",
      peak >> 20, format_byte_size(config.run.memory));
}

}  // namespace

std::filesystem::path result_path(const Config& config, TileKey key) {
  return config.project.work / "results" / (key.name() + ".bin");
}

TileStageReport process_tiles(const Config& config, const TileStore& store, const TileDigests& digests,
                              Cluster& cluster, const std::vector<std::size_t>& tiles,
                              std::span<const std::uint8_t> theirs) {
  if (digests.result.size() != store.tiles.size() || digests.inputs.size() != store.tiles.size()) {
    throw ProcessingError("process_tiles: one digest per tile is needed");
  }
  if (!theirs.empty() && theirs.size() != store.tiles.size()) {
    throw ProcessingError("process_tiles: the other processes' tiles are not given per tile");
  }
  std::filesystem::create_directories(config.project.work / "results");
  TileStageReport report;
  report.processed.assign(store.tiles.size(), 0);
  std::optional<WorkSchedule> schedule;
  std::size_t pending = tiles.size();
  std::uint64_t input = 0;
  if (cluster.root()) {
    std::vector<std::uint8_t> done = finished_items(config, store, digests.result, tiles);
    for (std::size_t item = 0; item < tiles.size(); ++item) {
      if (done[item] == 0) input += store.tiles[tiles[item]].owned();
    }
    pending = static_cast<std::size_t>(std::count(done.begin(), done.end(), 0));
    schedule.emplace(tile_schedule(store, tiles, theirs, std::move(done)));
    warn_tiles_over_budget(config, store, tiles);
  }
  Progress progress(pending, input, tiles.size() - pending);
  MemoryGate gate(config.run.memory);
  // Per item, each written by its worker only: made by its owner meanwhile, or kept.
  std::vector<std::uint8_t> finished_elsewhere(tiles.size(), 0);
  const std::unique_ptr<std::atomic<bool>[]> kept(new std::atomic<bool>[tiles.size()] {});
  const std::unique_ptr<std::atomic<bool>[]> mine(new std::atomic<bool>[tiles.size()] {});
  const bool several_ranks = cluster.size() > 1;
  const auto on_finish = [&](std::size_t item) {
    // Kept tiles count as reused: this process's workers say so, another rank's result does.
    const TileContents& tile = store.tiles[tiles[item]];
    if (kept[item].load() || (several_ranks && !mine[item].load() && kept_elsewhere(config, tile.key))) {
      ++report.kept;
      progress.kept(tile.owned());
      return;
    }
    report.processed[tiles[item]] = 1;
    ++report.count;
    progress.done(tile.owned());
  };
  // The channel ends (every rank's workers stopped) before the report is returned.
  auto channel = cluster.share(schedule ? &*schedule : nullptr, on_finish);
  run_workers(*channel, available_threads(), [&](std::size_t item) {
    const std::size_t k = tiles[item];
    const TileContents& tile = store.tiles[k];
    mine[item] = true;
    throw_if_interrupted("tile processing");
    if (!theirs.empty() && theirs[k] != 0 && has_finished_result(config, store, tile.key, digests.result[k])) {
      finished_elsewhere[item] = 1;  // its owner made it while this process did its own
      return;
    }
    const std::uint64_t estimate = tile_memory_estimate(tile);
    gate.acquire(estimate);
    // The memory earlier tiles freed stays resident for reuse (keep_freed_memory_for_reuse),
    // in each thread's arena: when that would take this tile past the budget, hand it back.
    if (const std::uint64_t resident = resident_bytes(); resident + estimate > config.run.memory) {
      log::debug("tile {}: {} MiB resident and {} MiB estimated: handing freed memory back", tile.key.name(),
                 resident >> 20, estimate >> 20);
      release_freed_memory();
    }
    try {
      const SettledSelection settled = settled_selection(config, store, k, digests.result);
      const ResultDigests own{digests.result[k], digests.inputs[k]};
      if (keep_if_still_right(result_path(config, tile.key), store, tile.key, own, settled)) {
        log::debug(
            "tile {}: the same inputs and border decisions (a neighbour was redone to the same, or its passes "
            "renumbered): its result is kept",
            tile.key.name());
        kept[item] = true;
      } else {
        const TileResult r = process_tile(store, tile.key, config, settled);
        write_tile_result(result_path(config, tile.key), r, own);
      }
    } catch (...) {
      gate.release(estimate);
      throw;
    }
    gate.release(estimate);
  });
  channel.reset();
  if (std::any_of(mine.get(), mine.get() + tiles.size(), [](const std::atomic<bool>& m) { return m.load(); })) {
    warn_if_past_budget(config);
  }
  for (std::size_t item = 0; item < tiles.size(); ++item) {
    if (finished_elsewhere[item] == 0) continue;
    report.processed[tiles[item]] = 0;
    --report.count;
  }
  if (cluster.root() && several_ranks) count_kept_elsewhere(config, store, tiles, report);
  return report;
}

}  // namespace citymesh::app
