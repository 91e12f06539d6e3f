// SPDX-License-Identifier: MIT
#include "mesh_edges.h"

#include "citymesh/mosaic/edges.h"

namespace citymesh::mosaic_detail {

MeshEdges mesh_edges(const Mesh& mesh, std::span<const std::uint8_t> in_subset) {
  MeshEdges out;
  out.boundary_length.assign(mesh.triangle_count(), 0.0);
  const std::vector<EdgeUse> uses = edge_uses(mesh.triangles, in_subset);
  for_each_edge(uses, [&](std::span<const EdgeUse> group) {
    const EdgeUse& e = group.front();
    const double length = norm(Vec3d(mesh.positions[e.lo]) - Vec3d(mesh.positions[e.hi]));
    out.edge_length_sum += length * double(group.size());
    out.edge_count += group.size();
    if (group.size() == 1) {
      out.boundary_length[e.triangle] += length;
    } else {
      for (std::size_t k = 0; k + 1 < group.size(); ++k) out.shared.push_back({group[k].triangle, group[k + 1].triangle, length});
    }
  });
  return out;
}

}  // namespace citymesh::mosaic_detail
