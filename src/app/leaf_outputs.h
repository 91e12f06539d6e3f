// SPDX-License-Identifier: MIT
// The mosaic's outputs written from the output's tiles one at a time (a tiled run whose seam
// pass ran block by block in files): the PLY and the picture.
#pragma once

#include <filesystem>

#include "seam_parts.h"

namespace citymesh::app {

/// Writes the output held by `leaves` as one PLY in the input format with the provenance
/// columns (source_acq, source_face), as write_mesh_ply writes a merged mesh: each vertex
/// once, numbered by the first tile (in key order) holding it, then by key; the faces tile by
/// tile. Holds a few tiles at a time.
void write_leaves_ply(const std::filesystem::path& path, const OutputLeaves& leaves);

}  // namespace citymesh::app
