// SPDX-License-Identifier: MIT
// The tiling stage: acquisitions tiled once each, shared between the ranks of a cluster.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>

#include "acquisitions.h"
#include "citymesh/core/error.h"
#include "citymesh/core/log.h"
#include "citymesh/core/parallel.h"
#include "citymesh/core/stopwatch.h"
#include "run_stages.h"

namespace citymesh::app {

namespace {

/// Each acquisition's bytes to tile (acquisition_bytes).
std::vector<std::uint64_t> file_sizes(std::span<const Acquisition> acquisitions) {
  std::vector<std::uint64_t> sizes;
  for (const Acquisition& a : acquisitions) sizes.push_back(acquisition_bytes(a));
  return sizes;
}

/// Which acquisition comes first: the largest file (a cluster), or the subset's own share
/// first, then the others in turn (a subset beside unknown others).
std::vector<std::uint64_t> tiling_priorities(std::span<const std::uint64_t> sizes,
                                             const std::optional<Subset>& subset) {
  if (!subset) return {sizes.begin(), sizes.end()};
  const std::size_t n = sizes.size(), start = (subset->index - 1) * n / subset->count;
  std::vector<std::uint64_t> priority(n);
  for (std::size_t k = 0; k < n; ++k) priority[k] = n - (k + n - start) % n;
  return priority;
}

std::string store_fingerprint(std::uint64_t fingerprint) { return fmt::format("{:016x}", fingerprint); }

std::vector<std::string> acquisition_fingerprints(const RunFingerprints& fingerprints) {
  std::vector<std::string> out;
  for (const std::uint64_t f : fingerprints.acquisitions) out.push_back(store_fingerprint(f));
  return out;
}

/// How many acquisitions a rank tiles at once: one per thread while each fits the budget
/// with its buffers and its vertices, held whole (about the size of its file). The result
/// does not depend on it: each acquisition is tiled alone, with the same buffers.
unsigned tiling_workers(std::span<const std::uint64_t> sizes, std::uint64_t memory, std::uint64_t buffer_bytes) {
  const std::uint64_t largest = sizes.empty() ? 0 : *std::max_element(sizes.begin(), sizes.end());
  const std::uint64_t fits = memory / std::max<std::uint64_t>(buffer_bytes + largest, 1);
  return static_cast<unsigned>(std::clamp<std::uint64_t>(fits, 1, available_threads()));
}

/// Says when some triangle reaches farther from its centroid than the halo less the distance
/// threshold: a tile may then miss a partner or a conflict of such a triangle that lies
/// beyond its halo, so labels near tile borders may differ from an untiled run's (long-range
/// sensors mesh far surfaces with long edges).
void warn_if_halo_too_narrow(const TileStore& store, const Config& config) {
  const double needed = store.stats.largest_radius + config.change.distance_threshold;
  if (needed <= store.grid.halo) return;
  log::warn(
      "tiling: some triangles reach {:.2f} m from their centroid, more than the halo ({} m) less the distance "
      "threshold ({} m): next to tile borders their labels may differ from an untiled run's; "
      "[tiling] halo = {:.1f} avoids it (a wider halo makes more copies)",
      store.stats.largest_radius, store.grid.halo, config.change.distance_threshold, std::ceil(needed * 10) / 10);
}

}  // namespace

std::optional<TileStore> finished_tile_store(const Config& config, const RunFingerprints& fingerprints) {
  std::optional<TileStore> store = read_tile_manifest(config.project.work / "tiles");
  if (!store || store->fingerprint != store_fingerprint(fingerprints.store)) return std::nullopt;
  return store;
}

namespace {

/// prepare_tile_store without the halo check: the store reused or made now.
TileStore reused_or_tiled_store(const Config& config, const RunFingerprints& fingerprints, Cluster& cluster,
                                const std::optional<Subset>& subset) {
  const std::filesystem::path dir = config.project.work / "tiles";
  const std::string wanted = store_fingerprint(fingerprints.store);
  const std::vector<std::string> wanted_each = acquisition_fingerprints(fingerprints);
  const std::optional<TileStore> existing = finished_tile_store(config, fingerprints);
  cluster.barrier();  // every rank has looked before any rank changes the store
  if (existing) {
    log::info("{}: reusing the tile store ({} tiles)", dir.string(), existing->tiles.size());
    return *existing;
  }
  Stopwatch clock;
  const std::vector<Acquisition> acquisitions = config.acquisition_list();
  const std::vector<std::uint64_t> sizes = file_sizes(acquisitions);
  // Only a run that owns the folder moves tilings and removes unfinished staging: subsets may
  // be tiling or reading there.
  if (cluster.root() && !subset) {
    std::filesystem::create_directories(dir);
    if (const std::size_t moved = move_renumbered_tilings(dir, wanted_each); moved > 0) {
      log::info("{}: the tiling of {} renumbered acquisition(s) moved to their new index, not made again", dir.string(),
                moved);
    }
  }
  if (cluster.root()) prune_tile_store(dir, wanted_each, wanted, !subset);

  TilerParams params;
  params.grid = {config.tiling.tile_size, config.tiling.halo, config.tiling.origin};
  params.ply = config.ply_read_params();
  params.dir = dir;
  params.buffer_bytes = std::max<std::uint64_t>(config.run.memory / 4, 16ull << 20);
  std::optional<WorkSchedule> schedule;
  if (cluster.root()) {
    std::vector<std::uint8_t> done(acquisitions.size());
    for (std::size_t k = 0; k < acquisitions.size(); ++k) {
      done[k] = read_acquisition_tiling(dir, static_cast<std::uint32_t>(k), wanted_each[k]).has_value() ? 1 : 0;
    }
    if (const auto kept = std::count(done.begin(), done.end(), 1); kept > 0) {
      log::info("{}: reusing the tiling of {} of {} acquisitions", dir.string(), kept, acquisitions.size());
    }
    schedule.emplace(tiling_priorities(sizes, subset), std::vector<std::vector<std::size_t>>(acquisitions.size()),
                     done);
  }
  {
    const auto channel = cluster.share(schedule ? &*schedule : nullptr, nullptr);
    run_workers(*channel, tiling_workers(sizes, config.run.memory, params.buffer_bytes),
                [&](std::size_t k) { (void)tile_acquisition(acquisitions[k], params, wanted_each[k]); });
  }
  if (cluster.root()) {
    std::vector<AcquisitionTiling> parts;
    for (std::uint32_t k = 0; k < acquisitions.size(); ++k) {
      std::optional<AcquisitionTiling> part = read_acquisition_tiling(dir, k, wanted_each[k]);
      if (!part)
        throw ProcessingError(
            fmt::format("{}: the tiled acquisition vanished", acquisition_tiles_path(dir, k).string()));
      parts.push_back(std::move(*part));
    }
    TileStore store = assemble_tile_store(dir, params.grid, parts, wanted);
    write_tile_manifest(store);
    log::info("tiled {} acquisitions into {} tiles in {:.2f} s", acquisitions.size(), store.tiles.size(),
              clock.seconds());
  }
  cluster.barrier();
  std::optional<TileStore> store = finished_tile_store(config, fingerprints);
  if (!store) {
    throw ProcessingError(
        fmt::format("{}: no finished tile store after tiling (is the work folder shared by every "
                    "rank?)",
                    dir.string()));
  }
  return *store;
}

}  // namespace

TileStore prepare_tile_store(const Config& config, const RunFingerprints& fingerprints, Cluster& cluster,
                             const std::optional<Subset>& subset) {
  // Before any work, and even when the tiling is reused (it depends on neither the CRS nor a
  // face element being there): a point cloud or a file in another CRS would give an empty map
  // or one elsewhere on Earth. Every rank looks, so that all stop alike.
  for (const Acquisition& a : config.acquisition_list()) check_acquisition_file(config, a);
  TileStore store = reused_or_tiled_store(config, fingerprints, cluster, subset);
  // Nothing to process: said here, rather than by an output step failing on an empty map.
  if (store.tiles.empty()) {
    throw InputError(
        fmt::format("{}: the acquisitions hold no triangle (every file is empty, or withdrawn)", config.file.string()));
  }
  if (cluster.root()) warn_if_halo_too_narrow(store, config);
  return store;
}

}  // namespace citymesh::app
