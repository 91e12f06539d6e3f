// SPDX-License-Identifier: MIT
#include "citymesh/mosaic/merged_mesh.h"

namespace citymesh {

namespace {

/// An attribute is kept only when every input has it.
void drop_partial_attributes(std::span<const Mesh> meshes, Mesh& out) {
  for (const Mesh& m : meshes) {
    if (m.sensor_positions.empty()) out.sensor_positions.clear();
    if (m.times.empty()) out.times.clear();
    if (m.intensities.empty()) out.intensities.clear();
    if (m.colors.empty()) out.colors.clear();
  }
}

}  // namespace

MergedMesh merge_selection(std::span<const Mesh> meshes, const GlobalTriangles& index,
                           std::span<const std::uint8_t> selected) {
  MergedMesh out;
  if (!meshes.empty()) out.mesh.origin = meshes.front().origin;
  for (std::size_t a = 0; a < meshes.size(); ++a) {
    const Mesh& m = meshes[a];
    std::vector<std::uint32_t> new_index(m.vertex_count(), UINT32_MAX);
    for (std::size_t t = 0; t < m.triangle_count(); ++t) {
      if (selected[index.offsets[a] + t] == 0) continue;
      Triangle tri = m.triangles[t];
      for (std::uint32_t& v : tri) {
        if (new_index[v] == UINT32_MAX) {
          new_index[v] = static_cast<std::uint32_t>(out.mesh.positions.size());
          append_vertex(m, v, out.mesh);
        }
        v = new_index[v];
      }
      out.mesh.triangles.push_back(tri);
      if (!m.triangle_ids.empty()) out.mesh.triangle_ids.push_back(m.triangle_ids[t]);
      out.source_acq.push_back(static_cast<std::int32_t>(a));
      out.source_triangle.push_back(static_cast<std::int32_t>(t));
    }
  }
  drop_partial_attributes(meshes, out.mesh);
  if (out.mesh.triangle_ids.size() != out.mesh.triangles.size()) out.mesh.triangle_ids.clear();
  return out;
}

void shrink_to_fit(MergedMesh& m) {
  m.mesh.shrink_to_fit();
  m.source_acq.shrink_to_fit();
  m.source_triangle.shrink_to_fit();
}

std::vector<std::uint64_t> source_sizes(const MergedMesh& m) {
  std::vector<std::uint64_t> sizes;
  for (const std::int32_t s : m.source_acq) {
    if (s < 0) continue;
    if (sizes.size() <= static_cast<std::size_t>(s)) sizes.resize(static_cast<std::size_t>(s) + 1, 0);
    ++sizes[static_cast<std::size_t>(s)];
  }
  return sizes;
}

}  // namespace citymesh
