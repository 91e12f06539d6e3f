// SPDX-License-Identifier: MIT
// Closing the small gaps left between pieces (internal to stitching, after snapping and
// zippering): where three pieces meet, or a boundary bends away from its neighbour's, the
// snapped boundaries enclose a small hole that no strip spans. Such a hole is bounded by
// more than one source; a hole bounded by one source alone is a hole of that scan (a window,
// a shadow) and stays open.
#pragma once

#include <cstdint>

#include "mesh_topology.h"

namespace citymesh::mosaic_detail {

/// The longest gap stitching closes, in gap widths: 2 m around at 10 cm, a crack, not a window.
constexpr double kGapPerimeterInWidths = 20.0;

struct GapFillParams {
  double max_width = 0.1;       ///< metres: twice the area over the perimeter (a strip's width)
  double max_perimeter = 2.0;   ///< metres
  std::size_t max_vertices = 32;
};

struct GapFillStats {
  std::uint64_t gaps_filled = 0;
  std::uint64_t triangles_added = 0;
  std::uint64_t gaps_split = 0;    ///< closed by splitting the loop's longest edge instead
  std::uint64_t gaps_refused = 0;  ///< small mixed-source loops no triangulation could close
};

/// Fills every boundary loop of `topo`'s mesh that runs along the edges of at least two
/// sources (stitch triangles count as one) and is small: at most `max_vertices` vertices,
/// `max_perimeter` long and `max_width` wide. A loop is triangulated by ear clipping in the
/// plane of its mean normal, shortest diagonal first. At a pinched vertex (one that starts
/// two boundary edges) a loop follows its own hole. When the fill would turn against the
/// triangle across one of its loop edges (a loop winding the wrong way, where two boundaries
/// cross), degenerate or reuse a directed edge, the loop is closed instead by splitting its
/// longest edge at its other vertices (split_boundary_edge_onto: moved onto it if need be,
/// by at most max_width), or left open when that would flip a triangle. New fill triangles
/// have source kNoSource; split ones keep theirs.
/// Deterministic: loops are taken from their smallest half-edge, in increasing order.
GapFillStats fill_seam_gaps(MeshTopology& topo, const GapFillParams& params);

}  // namespace citymesh::mosaic_detail
