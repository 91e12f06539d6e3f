// SPDX-License-Identifier: MIT
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <set>

#include "citymesh/tiles3d/simplify.h"
#include "grid_triangles.h"

namespace citymesh {
namespace {

struct Grid {
  std::vector<Vec3f> positions;
  std::vector<Triangle> triangles;
};

/// A gently curved n x n grid (0.5 m cells) with a square hole in the middle.
Grid holed_grid(int n) {
  Grid g;
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j <= n; ++j)
      g.positions.push_back({0.5f * float(i), 0.5f * float(j), 0.01f * float((i - n / 2) * (i - n / 2))});
  g.triangles = test::grid_triangles(n, [n](int i, int j) { return std::abs(i - n / 2) >= 3 || std::abs(j - n / 2) >= 3; });
  return g;
}

/// Vertices on an edge used by exactly one triangle.
std::set<std::uint32_t> border_vertices(const std::vector<Triangle>& triangles) {
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> uses;
  for (const Triangle& t : triangles)
    for (int k = 0; k < 3; ++k) ++uses[std::minmax(t[k], t[(k + 1) % 3])];
  std::set<std::uint32_t> out;
  for (const auto& [edge, n] : uses)
    if (n == 1) out.insert({edge.first, edge.second});
  return out;
}

TEST(Simplify, ReducesTrianglesAndKeepsEveryBorderVertex) {
  const Grid g = holed_grid(40);
  const SimplifiedMesh s = simplify_mesh(g.positions, g.triangles, {.target_ratio = 0.25, .max_error_fraction = 0.05,
                                                                    .lock_border = true});
  EXPECT_LT(s.triangles.size(), g.triangles.size() / 2);
  EXPECT_GT(s.error, 0.0);
  EXPECT_LT(s.error, 0.5);  // metres: the grid is 20 m across and barely curved
  std::set<std::uint32_t> used;
  for (const Triangle& t : s.triangles) used.insert(t.begin(), t.end());
  for (const std::uint32_t v : border_vertices(g.triangles)) EXPECT_TRUE(used.count(v)) << v;
  // The borders (outer edge and hole) are still exactly where they were.
  EXPECT_EQ(border_vertices(s.triangles), border_vertices(g.triangles));
}

TEST(Simplify, UnlockedBordersSimplifyFurther) {
  const Grid g = holed_grid(40);
  const auto locked = simplify_mesh(g.positions, g.triangles, {.target_ratio = 0.05, .max_error_fraction = 0.05,
                                                               .lock_border = true});
  const auto free = simplify_mesh(g.positions, g.triangles, {.target_ratio = 0.05, .max_error_fraction = 0.05,
                                                             .lock_border = false});
  EXPECT_LT(free.triangles.size(), locked.triangles.size());
}

TEST(Simplify, EmptyInputGivesEmptyOutput) {
  const SimplifiedMesh s = simplify_mesh({}, {}, {});
  EXPECT_TRUE(s.triangles.empty());
  EXPECT_EQ(s.error, 0.0);
}

}  // namespace
}  // namespace citymesh
