// SPDX-License-Identifier: MIT
// `citymesh run` on the tile store: tile the acquisitions (or reuse the store), process the
// tiles in parallel within the memory budget (reusing finished ones), then assemble, stitch
// across tiles and write the outputs.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>

#include "citymesh/config/config.h"
#include "cluster.h"
#include "pipeline.h"
#include "tile_plan.h"

namespace citymesh::app {

struct TiledRunOptions {
  bool force = false;  ///< discard work done with another config instead of refusing
  PictureOptions pictures;
  /// Only this part of the tiles, and no outputs (`citymesh merge` writes them).
  std::optional<Subset> subset;
  /// Tile what is not tiled yet, then say what the run would do with each tile and stop
  /// (run_plan.h): no tile processed, no output written, the run config not recorded.
  bool plan = false;
};

/// Runs every step tile by tile, on this process or on every rank of `cluster`; see
/// docs/tiling.md and docs/cluster.md. Throws ConfigError when the work folder holds work made
/// with a different result-affecting config and `force` is not set.
void run_tiled(const Config& config, const TiledRunOptions& options, Cluster& cluster);

/// `citymesh merge`: the outputs of a run whose tiles were all processed (by subsets). Throws
/// InputError naming the tiles without a finished result.
void merge_tiled(const Config& config, const PictureOptions& pictures);

/// The config keys that change results (input, change, mosaic, tiling, the acquisitions and
/// their files' sizes and modification times), flattened as "section.key" -> TOML value.
std::map<std::string, std::string> result_keys(const Config& config);

}  // namespace citymesh::app
