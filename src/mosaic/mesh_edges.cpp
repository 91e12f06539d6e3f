// SPDX-License-Identifier: MIT
#include "mesh_edges.h"

#include <algorithm>
#include <tuple>

namespace citymesh::mosaic_detail {

MeshEdges mesh_edges(const Mesh& mesh, std::span<const std::uint8_t> in_subset) {
  struct HalfEdge {
    std::uint32_t lo, hi, triangle;
    auto operator<=>(const HalfEdge&) const = default;
  };
  std::vector<HalfEdge> edges;
  MeshEdges out;
  out.boundary_length.assign(mesh.triangle_count(), 0.0);
  for (std::uint32_t t = 0; t < mesh.triangle_count(); ++t) {
    if (in_subset[t] == 0) continue;
    const Triangle& tri = mesh.triangles[t];
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t u = tri[k], v = tri[(k + 1) % 3];
      edges.push_back({std::min(u, v), std::max(u, v), t});
    }
  }
  std::sort(edges.begin(), edges.end());
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i + 1;
    while (j < edges.size() && edges[j].lo == edges[i].lo && edges[j].hi == edges[i].hi) ++j;
    const double length = norm(Vec3d(mesh.positions[edges[i].lo]) - Vec3d(mesh.positions[edges[i].hi]));
    out.edge_length_sum += length * double(j - i);
    out.edge_count += j - i;
    if (j - i == 1) {
      out.boundary_length[edges[i].triangle] += length;
    } else {
      for (std::size_t k = i; k + 1 < j; ++k) out.shared.push_back({edges[k].triangle, edges[k + 1].triangle, length});
    }
    i = j;
  }
  return out;
}

}  // namespace citymesh::mosaic_detail
