// SPDX-License-Identifier: MIT
#include "citymesh/mosaic/merged_mesh.h"

#include <algorithm>
#include <numeric>
#include <unordered_map>

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

std::vector<std::int32_t> source_pieces(const MergedMesh& m) {
  const std::size_t n = m.mesh.triangle_count();
  // Union-find over the triangles; a root is always its set's smallest index, so that the
  // names do not depend on the order of the unions.
  std::vector<std::uint32_t> parent(n);
  std::iota(parent.begin(), parent.end(), 0U);
  const auto find = [&](std::uint32_t t) {
    while (parent[t] != t) t = parent[t] = parent[parent[t]];
    return t;
  };
  const auto unite = [&](std::uint32_t a, std::uint32_t b) {
    a = find(a);
    b = find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  };
  std::vector<std::uint32_t> first_at(m.mesh.vertex_count(), UINT32_MAX);  ///< first sourced triangle at v
  // (vertex, source) -> a triangle, for the few vertices that several sources share (a seam
  // stitched before, in a pass part by part).
  std::unordered_map<std::uint64_t, std::uint32_t> shared;
  for (std::uint32_t t = 0; t < n; ++t) {
    const std::int32_t s = m.source_acq[t];
    if (s < 0) continue;
    for (const std::uint32_t v : m.mesh.triangles[t]) {
      const std::uint32_t u = first_at[v];
      if (u == UINT32_MAX) {
        first_at[v] = t;
      } else if (m.source_acq[u] == s) {
        unite(u, t);
      } else {
        const auto [it, added] = shared.try_emplace((std::uint64_t{v} << 32) | static_cast<std::uint32_t>(s), t);
        if (!added) unite(it->second, t);
      }
    }
  }
  std::vector<std::int32_t> piece(n, kNoSource);
  for (std::uint32_t t = 0; t < n; ++t) {
    if (m.source_acq[t] >= 0) piece[t] = static_cast<std::int32_t>(find(t));
  }
  return piece;
}

}  // namespace citymesh
