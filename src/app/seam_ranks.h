// SPDX-License-Identifier: MIT
// The seam pass by blocks shared by the ranks of an MPI job: the root files the output by
// part and measures it; the parts of each stitching level are handed out to every rank like
// tiles (the parts of one level never meet), each rank reading and writing them in the root's
// folder on the shared filesystem.
#pragma once

#include "citymesh/config/config.h"
#include "citymesh/mosaic/stitch_blocks.h"
#include "cluster.h"
#include "mosaic_step.h"
#include "seam_parts.h"

namespace citymesh::app {

/// On the root: the seam pass's work shared with every rank. Each step (the open boundary
/// measured, each level stitched, the boundary measured again) writes its plan to the work
/// folder and hands its parts out (collective: the other ranks are in help_seam_pass()).
/// `files` (with the sources' sizes clipping ranks by) and `cluster` must outlive it.
SeamPassWork share_seam_pass(const Config& config, Cluster& cluster, const SeamPartFiles& files);

/// Removes the plan share_seam_pass() left in the work folder, once the pass is done.
void remove_seam_plan(const Config& config);

/// On every other rank, while the root runs its seam pass by blocks: measures and stitches
/// the parts the root hands it, step by step. Collective with share_seam_pass().
void help_seam_pass(const Config& config, Cluster& cluster);

}  // namespace citymesh::app
