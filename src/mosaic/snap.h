// SPDX-License-Identifier: MIT
// Snapping (internal to stitching): boundaries of pieces from different sources that lie on
// top of each other are made to share vertices, so that the seam between them closes
// without a strip of new triangles (a strip between nearly coincident boundaries is all
// slivers, and half of them flip).
#pragma once

#include <cstdint>
#include <vector>

#include "mesh_topology.h"

namespace citymesh::mosaic_detail {

struct SnapStats {
  std::uint64_t vertices_merged = 0;  ///< pairs of boundary vertices of different sources made one
  std::uint64_t edges_split = 0;      ///< boundary edges split at a vertex of another source
  std::uint64_t rejected = 0;  ///< merges and splits refused (a flip, a degenerate or a non-manifold result)
};

/// Splits the triangle on the directed edge from -> to into a fan through `inserted` (in
/// order from `from` to `to`), unless a piece would flip or degenerate against the triangle
/// or reuse a directed edge; the pieces keep its provenance. Returns whether it did.
bool split_boundary_edge(MeshTopology& topo, std::uint32_t from, std::uint32_t to, const std::vector<std::uint32_t>& inserted);

/// As split_boundary_edge; when the fan would fold or degenerate (typically the edge's
/// triangle is a thin cut triangle and a vertex lies beyond its apex, where two clipped
/// boundaries cross), the vertices are first moved onto the edge, by at most `max_move` each
/// and only if none of their own triangles flips or degenerates. The moves are undone if the
/// split still fails. Returns whether it split.
bool split_boundary_edge_onto(MeshTopology& topo, std::uint32_t from, std::uint32_t to,
                              const std::vector<std::uint32_t>& inserted, double max_move);

/// First merges each boundary vertex with the nearest boundary vertex of another source
/// within `tolerance` (both move to their midpoint), then splits each boundary edge at the
/// boundary vertices of other sources within `tolerance` of it (the edge's triangle becomes a
/// fan; the new triangles keep its provenance; where that fan would fold, as over a sliver cut
/// triangle, the vertices are moved onto the edge first: split_boundary_edge_onto). An operation is skipped when a triangle would
/// flip or degenerate, or a directed edge would be used twice (the mesh stays edge-manifold
/// and consistently oriented). Frozen vertices (MeshTopology) never move: a free vertex merged
/// with one goes to it, and no triangle of frozen corners is split. Deterministic: vertices
/// and edges in index order. The mesh is
/// topo's, which is kept up to date.
SnapStats snap_boundaries(MeshTopology& topo, double tolerance);

}  // namespace citymesh::mosaic_detail
