// SPDX-License-Identifier: MIT
// The stages of a tiled run, shared by `citymesh run` (one process or the ranks of an MPI job),
// `citymesh run --subset i/N` and `citymesh merge`.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <span>
#include <vector>

#include "citymesh/config/config.h"
#include "citymesh/tiler/tiler.h"
#include "cluster.h"
#include "run_state.h"
#include "tile_plan.h"

namespace citymesh::app {

/// <work>/results/<tile>.bin
std::filesystem::path result_path(const Config& config, TileKey key);

/// The finished tile store in <work>/tiles when it was made with `fingerprints.store`;
/// nothing otherwise.
std::optional<TileStore> finished_tile_store(const Config& config, const RunFingerprints& fingerprints);

/// The tile store of `config`: the finished one in <work>/tiles when it was made with
/// `fingerprints.store`, otherwise made now. Acquisitions already tiled with their own
/// fingerprint (`fingerprints.acquisitions`) are kept, so that appending one tiles only it;
/// the others are handed out to the ranks of `cluster`, largest file first. A subset (which
/// may run beside other subsets, unknown to it) takes them in turn starting at its own share,
/// so that subsets started together tile different acquisitions. Collective.
TileStore prepare_tile_store(const Config& config, const RunFingerprints& fingerprints, Cluster& cluster,
                             const std::optional<Subset>& subset);

struct TileStageReport {
  std::vector<std::uint8_t> processed;  ///< per store tile: processed now (not reused)
  std::size_t count = 0;                ///< tiles processed now
  /// Tiles whose result was kept when a neighbour was redone (not among `processed`).
  std::size_t kept = 0;
};

/// Processes every tile of `tiles` (indices into store.tiles, closed under
/// tile_dependencies) that has no finished result under its digest (`digests.result`), each
/// once its dependencies are done; a result made from the same inputs and the same decisions
/// of the neighbours on the tile's halo is kept instead (written again under the new digest),
/// largest first, on the worker threads of every rank within each rank's memory budget.
/// Results go to <work>/results. Collective; the report is complete on the root only.
/// `theirs` (per store tile, or empty): tiles another process owns (a subset's dependencies
/// in other subsets). They are taken only when nothing else is ready, and skipped when their
/// result has appeared meanwhile, so subsets started together redo fewer of each other's.
TileStageReport process_tiles(const Config& config, const TileStore& store, const TileDigests& digests,
                              Cluster& cluster, const std::vector<std::size_t>& tiles,
                              std::span<const std::uint8_t> theirs = {});

}  // namespace citymesh::app
