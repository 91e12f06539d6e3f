// SPDX-License-Identifier: MIT
// The assembly of a tiled run's results shared by the ranks of an MPI job (seam pass by
// blocks): every rank reads tile results and files their selected triangles under the seam
// parts in the root's folder, then merges parts' fragments into their input files; the root
// adds up what each tile's filing reports, in tile order, so the output is one process's.
#pragma once

#include <cstdint>
#include <functional>
#include <nlohmann/json.hpp>
#include <span>
#include <vector>

#include "citymesh/config/config.h"
#include "cluster.h"
#include "seam_parts.h"
#include "tile_assembly.h"

namespace citymesh::app {

/// One tile's result read and its selected triangles filed: what the root adds for it.
struct FiledResult {
  SeamPartFiles::FiledTile filed;
  TileTally tally;
};

/// What a rank leaves beside the parts for the root: a tile's filing and tally as JSON
/// (doubles and boxes as their bits, so that the root's sums are one process's), and back
/// (throws nlohmann::json::exception or ProcessingError when a field is missing).
nlohmann::json filed_result_json(const FiledResult& r);
FiledResult filed_result_from(const nlohmann::json& j);

/// Reads the result of tile `k` of `store` (made under `digest`) without its pairs and files
/// its selected triangles under their parts in `files`' folder. Throws ProcessingError naming
/// the file when the result cannot be read (resuming checked it whole before).
FiledResult file_tile_result(const Config& config, const TileStore& store, std::size_t k, std::uint64_t digest,
                             const SeamPartFiles& files);

/// Per tile, what reading its result is estimated to hold (0 when the file is missing: the
/// read then reports it).
std::vector<std::uint64_t> result_read_bytes(const Config& config, const TileStore& store);

/// How many results each process reads at once, given result_read_bytes(): its threads, fewer
/// when the budget left does not hold that many of the largest (a spinning street's results
/// reach 0.3 GB each).
unsigned results_at_once(const Config& config, std::span<const std::uint64_t> bytes);

/// On the root: the assembly's two steps shared with every rank (collective: the other ranks
/// are in help_assembly()). `files` and `cluster` must outlive it.
struct AssemblyWork {
  /// Every tile's result read and filed, in tile order; `here(k)` does tile k in this process.
  std::function<std::vector<FiledResult>(const std::function<FiledResult(std::size_t)>& here)> file_tiles;
  /// Every part's fragments merged (SeamPartFiles::finish).
  SeamPartFiles::PartMerging merge_parts;
};
AssemblyWork share_assembly(const Config& config, Cluster& cluster, const SeamPartFiles& files, const TileStore& store);

/// Removes the plan share_assembly() left in the work folder, once the assembly is done.
void remove_assembly_plan(const Config& config);

/// On every other rank, while the root assembles: reads and files the tiles, then merges the
/// parts, the root hands it. Collective with share_assembly(); `digests` as the root's.
void help_assembly(const Config& config, Cluster& cluster, const TileStore& store,
                   std::span<const std::uint64_t> digests);

}  // namespace citymesh::app
