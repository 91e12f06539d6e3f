// SPDX-License-Identifier: MIT
// Edge adjacency of a subset of one mesh's triangles.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "citymesh/core/mesh.h"

namespace citymesh::mosaic_detail {

struct SharedEdge {
  std::uint32_t a = 0, b = 0;  ///< triangles (mesh-local) on either side
  double length = 0;           ///< metres
};

struct MeshEdges {
  std::vector<SharedEdge> shared;      ///< edges between two triangles of the subset
  std::vector<double> boundary_length;  ///< per triangle: its edges no other subset triangle shares
  double edge_length_sum = 0;          ///< over every edge of every subset triangle
  std::uint64_t edge_count = 0;
};

/// Adjacency among the triangles t with in_subset[t] != 0. An edge of more than two triangles
/// (non-manifold) links each to the next in index order.
MeshEdges mesh_edges(const Mesh& mesh, std::span<const std::uint8_t> in_subset);

}  // namespace citymesh::mosaic_detail
