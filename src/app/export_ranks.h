// SPDX-License-Identifier: MIT
// The 3D Tiles export shared by the ranks of an MPI job: the leaves to map to the local frame
// (the first pass) and the tree's cells (each a subtree of grid tiles, built depth first) are
// handed out to every rank like tiles, each rank reading the output's tiles and writing its
// tiles' glb files in the root's folders on the shared filesystem; the root builds the levels
// above the cells.
#pragma once

#include "citymesh/config/config.h"
#include "citymesh/tiles3d/export.h"
#include "cluster.h"
#include "seam_parts.h"

namespace citymesh::app {

/// On the root: the export's leaves to map and cells to build handed out to every rank
/// (collective when called: the other ranks are in help_export()). `config`, `cluster` and
/// `leaves` must outlive it.
ExportWork share_export(const Config& config, Cluster& cluster, const OutputLeaves& leaves);

/// On the root, once the export is written (or when there is none): lets the other ranks out
/// of help_export() and removes the plan. Collective.
void end_shared_export(const Config& config, Cluster& cluster);

/// On every other rank, after help_seam_pass(): maps the leaves and builds the cells the root
/// hands it until the root ends the export. Collective with share_export() and end_shared_export().
void help_export(const Config& config, Cluster& cluster);

}  // namespace citymesh::app
