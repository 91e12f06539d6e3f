// SPDX-License-Identifier: MIT
// Stitching (paper §IV): the selected triangles form pieces, one source each; where the
// boundaries of pieces from different sources face each other, strips of new triangles join
// them (zippering), and vertices closer than a small tolerance are merged.
#pragma once

#include <cstdint>

#include "citymesh/mosaic/merged_mesh.h"

namespace citymesh {

struct StitchParams {
  double reach = 0.2;   ///< metres: boundaries of different sources closer than this are joined
  double weld = 0.005;  ///< metres: strip corners closer than this become one vertex
};

struct StitchStats {
  double open_boundary_before = 0, open_boundary_after = 0;  ///< metres of edges used by one triangle
  std::uint64_t strips = 0, triangles_added = 0, vertices_welded = 0;
  std::uint64_t rejected = 0;  ///< strip triangles refused (flipped against a neighbour or degenerate)
  double seconds = 0;
};

/// Joins facing boundaries of pieces from different sources of `mesh` with strips of new
/// triangles (source kNoSource), advancing along both boundaries and taking the shorter
/// diagonal at each step; a strip triangle is only added when it is not degenerate and faces
/// the same way as the piece triangles beside it. Deterministic.
StitchStats stitch(MergedMesh& mesh, const StitchParams& params);

/// Total length of the edges used by exactly one triangle.
double open_boundary_length(const Mesh& mesh);

}  // namespace citymesh
