// SPDX-License-Identifier: MIT
// The seam pass by blocks shared by the ranks of an MPI job: the root files the output by
// part and measures it; the parts of each stitching level are handed out to every rank like
// tiles (the parts of one level never meet), each rank reading and writing them in the root's
// folder on the shared filesystem.
#pragma once

#include <span>

#include "citymesh/config/config.h"
#include "citymesh/mosaic/stitch_blocks.h"
#include "cluster.h"
#include "seam_parts.h"

namespace citymesh::app {

/// On the root: a PartStitchRun::run_level that writes the level's plan to the work folder
/// and shares its parts with every rank (collective: the other ranks are in
/// help_seam_pass()). `files` and `cluster` must outlive it.
decltype(PartStitchRun::run_level) share_seam_levels(const Config& config, Cluster& cluster,
                                                     const SeamPartFiles& files,
                                                     std::span<const std::uint64_t> source_sizes);

/// Removes the plan share_seam_levels() left in the work folder, once the pass is done.
void remove_seam_plan(const Config& config);

/// On every other rank, while the root runs its seam pass by blocks: stitches the parts of
/// each level the root hands it. Collective with share_seam_levels().
void help_seam_pass(const Config& config, Cluster& cluster);

}  // namespace citymesh::app
