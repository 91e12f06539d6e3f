// SPDX-License-Identifier: MIT
// Meshes and checks shared by the stitching tests.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <map>
#include <set>
#include <utility>

#include "citymesh/core/geometry.h"
#include "citymesh/core/mesh.h"
#include "citymesh/mosaic/merged_mesh.h"

namespace citymesh::test {

/// A flat grid of nx x ny cells of size `step` at x0, split into triangles, normals +z
/// (counter-clockwise seen from above), appended to `out` with source `source`.
inline void add_grid(MergedMesh& out, float x0, float y0, int nx, int ny, float step, std::int32_t source, float z = 0) {
  const auto base = static_cast<std::uint32_t>(out.mesh.positions.size());
  for (int j = 0; j <= ny; ++j) {
    for (int i = 0; i <= nx; ++i) out.mesh.positions.push_back({x0 + float(i) * step, y0 + float(j) * step, z});
  }
  const auto id = [&](int i, int j) { return base + static_cast<std::uint32_t>(j * (nx + 1) + i); };
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      for (const Triangle& t : {Triangle{id(i, j), id(i + 1, j), id(i + 1, j + 1)}, Triangle{id(i, j), id(i + 1, j + 1), id(i, j + 1)}}) {
        out.mesh.triangles.push_back(t);
        out.mesh.triangle_ids.push_back({});
        out.source_acq.push_back(source);
        out.source_triangle.push_back(static_cast<std::int32_t>(out.source_triangle.size()));
      }
    }
  }
}

/// Four sources, each kind of seam crossing both axes: source 0 (3 x 3 m) with, 4 cm beyond
/// its side x = 3, a coarser source 1 (zippered); 1.5 cm beyond its side y = 3, source 2
/// (snapped); a small piece of source 3 lying 5 cm over source 0 (clipped).
inline MergedMesh four_source_scene() {
  MergedMesh m;
  add_grid(m, 0, 0, 30, 30, 0.1f, 0, 0);
  add_grid(m, 3.04f, 0.013f, 22, 27, 0.11f, 1, 0.01f);
  add_grid(m, 0, 3.015f, 30, 12, 0.1f, 2, 0.01f);
  add_grid(m, 1.25f, 1.3f, 8, 6, 0.1f, 3, 0.05f);
  return m;
}

/// Edges used by more than two triangles.
inline std::size_t non_manifold_edges(const Mesh& m) {
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> uses;
  for (const Triangle& t : m.triangles) {
    for (int k = 0; k < 3; ++k) ++uses[{std::min(t[k], t[(k + 1) % 3]), std::max(t[k], t[(k + 1) % 3])}];
  }
  return static_cast<std::size_t>(std::count_if(uses.begin(), uses.end(), [](const auto& u) { return u.second > 2; }));
}

/// Directed edges used by more than one triangle (a fold, or an orientation flip).
inline std::size_t repeated_directed_edges(const Mesh& m) {
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> uses;
  for (const Triangle& t : m.triangles) {
    for (int k = 0; k < 3; ++k) ++uses[{t[k], t[(k + 1) % 3]}];
  }
  return static_cast<std::size_t>(std::count_if(uses.begin(), uses.end(), [](const auto& u) { return u.second > 1; }));
}

/// A triangle by its corners' positions, to find it again after indices changed.
using Corners = std::array<std::array<float, 3>, 3>;

inline Corners corners_of(const MergedMesh& m, std::size_t t) {
  Corners c{};
  for (std::size_t k = 0; k < 3; ++k) {
    const Vec3f p = m.mesh.positions[m.mesh.triangles[t][k]];
    c[k] = {p.x, p.y, p.z};
  }
  return c;
}

template <class Chosen>
inline std::multiset<Corners> triangles_of(const MergedMesh& m, Chosen chosen) {
  std::multiset<Corners> out;
  for (std::size_t t = 0; t < m.mesh.triangle_count(); ++t) {
    if (chosen(t)) out.insert(corners_of(m, t));
  }
  return out;
}

inline bool contains_all(const std::multiset<Corners>& all, const std::multiset<Corners>& part) {
  return std::includes(all.begin(), all.end(), part.begin(), part.end());
}

/// Triangles facing down or of no area (every fixture faces +z).
inline std::size_t flipped_or_flat(const Mesh& m) {
  std::size_t bad = 0;
  for (std::size_t t = 0; t < m.triangle_count(); ++t) {
    const TriangleCorners c = m.corners(t);
    bad += cross(c[1] - c[0], c[2] - c[0]).z > 1e-9 ? 0 : 1;
  }
  return bad;
}

}  // namespace citymesh::test
