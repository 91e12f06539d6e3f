// SPDX-License-Identifier: MIT
// Triangulated vertex grids, the test meshes of the encode and tiles3d tests.
#pragma once

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

}  // namespace citymesh::test
