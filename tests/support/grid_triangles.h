// SPDX-License-Identifier: MIT
// Triangulated vertex grids, the test meshes of the encode, tiles3d and mosaic tests.
#pragma once

#include <functional>
#include <vector>

#include "citymesh/core/mesh.h"

namespace citymesh::test {

/// The triangles of a grid of (n + 1) x (n + 1) vertices numbered i * (n + 1) + j: two per
/// cell (i, j), {a, a + n + 1, a + 1} and {a + 1, a + n + 1, a + n + 2}, cells in (i, j)
/// order, for the cells `keep(i, j)` accepts.
template <class Keep>
std::vector<Triangle> grid_triangles(int n, Keep keep) {
  std::vector<Triangle> out;
  const auto s = static_cast<std::uint32_t>(n + 1);
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      if (!keep(i, j)) continue;
      const auto a = static_cast<std::uint32_t>(i) * s + static_cast<std::uint32_t>(j);
      out.push_back({a, a + s, a + 1});
      out.push_back({a + 1, a + s, a + s + 1});
    }
  }
  return out;
}

inline std::vector<Triangle> grid_triangles(int n) {
  return grid_triangles(n, [](int, int) { return true; });
}

/// A grid of columns x rows cells whose vertex (i, j) is numbered j (columns + 1) + i and sits
/// at place(i, j): two triangles per cell, {(i, j), (i + 1, j), (i + 1, j + 1)} then
/// {(i, j), (i + 1, j + 1), (i, j + 1)}, cells row by row (cell (i, j) holds triangles
/// 2 (j columns + i) and the next). A flat grid, or one folded wherever place bends.
inline Mesh placed_grid(int columns, int rows, const std::function<Vec3f(int, int)>& place) {
  Mesh m;
  for (int j = 0; j <= rows; ++j) {
    for (int i = 0; i <= columns; ++i) m.positions.push_back(place(i, j));
  }
  const auto id = [&](int i, int j) { return static_cast<std::uint32_t>(j * (columns + 1) + i); };
  for (int j = 0; j < rows; ++j) {
    for (int i = 0; i < columns; ++i) {
      m.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      m.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  }
  m.triangle_ids.resize(m.triangles.size());
  return m;
}

}  // namespace citymesh::test
