// SPDX-License-Identifier: MIT
// The end of a run's final pass shared by the ranks of an MPI job, once the seam pass is
// stitched (seam_ranks.h): the stitched parts filed by grid tile of the output, then the 3D
// Tiles export's first pass (the leaves mapped to the local frame) and its tree's cells
// (subtrees of grid tiles, built depth first). Each step is handed out like tiles; every rank
// reads and writes in the root's folders on the shared filesystem, and the root builds the
// export's levels above the cells.
#pragma once

#include <filesystem>
#include <vector>

#include "citymesh/config/config.h"
#include "citymesh/mosaic/stitch_blocks.h"
#include "citymesh/tiles3d/export.h"
#include "cluster.h"
#include "seam_parts.h"
#include "tileset_output.h"

namespace citymesh::app {

/// On the root: the filing of the stitched parts `parts` (in `parts_dir`) by grid tile
/// handed out to every rank (collective when called: the other ranks are in help_outputs()).
/// `config` and `cluster` must outlive it.
LeafFilingWork share_leaf_filing(const Config& config, Cluster& cluster, const std::filesystem::path& parts_dir,
                                 std::vector<BlockPartKey> parts);

/// On the root: the export's leaves to map and cells to build handed out to every rank
/// (collective when called). `config`, `cluster` and `leaves` must outlive it.
ExportWork share_export(const Config& config, Cluster& cluster, const OutputLeaves& leaves);

/// On the root: the per-tile PLYs of `leaves` ([output] ply) handed out to every rank
/// (collective when called). `config`, `cluster` and `leaves` must outlive it.
LeafPlyWork share_leaf_plys(const Config& config, Cluster& cluster, const OutputLeaves& leaves);

/// On the root, once the outputs are written (or when there are none): lets the other ranks
/// out of help_outputs() and removes the plan. Collective.
void end_shared_outputs(const Config& config, Cluster& cluster);

/// On every other rank, after help_seam_pass(): files parts, maps leaves, builds cells and
/// writes per-tile PLYs as the root hands them out, until the root ends. Collective with the
/// four above.
void help_outputs(const Config& config, Cluster& cluster);

}  // namespace citymesh::app
