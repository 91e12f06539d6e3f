// SPDX-License-Identifier: MIT
// Internal to the mosaic module: whether another pass saw through the place where a triangle
// stands (the hole fill's visibility check).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "citymesh/change/detect.h"
#include "citymesh/core/mesh.h"

namespace citymesh::mosaic_detail {

struct SeenThroughParams {
  /// Points nearer a triangle's plane than this lie on its surface, not in front of it (the
  /// role of the change step's conflict margin; the mosaic uses the distance threshold).
  double margin = 0.1;
  /// Only empty space within this distance of the surface that bounds it is searched: the
  /// question is about surfaces standing just in front of another pass's surface (a window
  /// recess that one pass bridged and another saw into), and a short reach keeps the search
  /// to the triangles nearby.
  double depth = 1.0;
};

/// The check as the mosaic asks it, in the energy (seen_through_quality) and in the hole fill:
/// one definition, because the fill takes the energy's answers instead of asking again.
inline SeenThroughParams mosaic_visibility(double distance_threshold) { return {.margin = distance_threshold}; }

/// For each listed triangle (global ids of `index`), 1 when its centroid lies in the empty
/// space of a triangle of another mesh: inside the tetrahedron between that triangle and its
/// viewpoint (the barycentre of its corners' sensor positions), more than params.margin and at
/// most params.depth from the triangle's plane. Another pass then saw through the place where
/// it stands. Meshes without sensor positions see nothing. All meshes share one local frame.
/// Deterministic whatever the thread count.
std::vector<std::uint8_t> seen_through(std::span<const Mesh> meshes, const GlobalTriangles& index,
                                       std::span<const std::uint32_t> triangles, const SeenThroughParams& params);

}  // namespace citymesh::mosaic_detail
