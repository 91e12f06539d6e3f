// SPDX-License-Identifier: MIT
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <set>

#include "citymesh/core/error.h"
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

TEST(Simplify, LockedVerticesStayWhileTheOtherBordersGo) {
  // The outer border locked vertex by vertex, the hole's rim free: the outer border is kept
  // exactly (every vertex and edge), the rim is simplified, and the count drops further than
  // with every border locked.
  const int n = 40;
  const Grid g = holed_grid(n);
  std::vector<std::uint8_t> outer(g.positions.size(), 0);
  std::set<std::uint32_t> outer_set;
  for (int i = 0; i <= n; ++i) {
    for (int j = 0; j <= n; ++j) {
      if (i == 0 || j == 0 || i == n || j == n) {
        outer[static_cast<std::size_t>(i * (n + 1) + j)] = 1;
        outer_set.insert(static_cast<std::uint32_t>(i * (n + 1) + j));
      }
    }
  }
  const SimplifyParams free_borders{.target_ratio = 0.02, .max_error_fraction = 0.05, .lock_border = false};
  const SimplifiedMesh s = simplify_mesh(g.positions, g.triangles, free_borders, outer);
  std::set<std::uint32_t> s_border;
  for (const std::uint32_t v : border_vertices(s.triangles)) {
    if (outer_set.count(v) != 0) s_border.insert(v);
  }
  EXPECT_EQ(s_border, outer_set);  // every outer vertex still on the border
  std::set<std::uint32_t> rim = border_vertices(g.triangles), rim_kept = border_vertices(s.triangles);
  for (const std::uint32_t v : outer_set) {
    rim.erase(v);
    rim_kept.erase(v);
  }
  EXPECT_LT(rim_kept.size(), rim.size());  // the hole's rim simplified
  const SimplifiedMesh all_locked =
      simplify_mesh(g.positions, g.triangles, {.target_ratio = 0.02, .max_error_fraction = 0.05, .lock_border = true});
  EXPECT_LT(s.triangles.size(), all_locked.triangles.size());
  // Without the locks the outer border moves.
  const SimplifiedMesh unlocked = simplify_mesh(g.positions, g.triangles, free_borders);
  std::size_t outer_kept = 0;
  for (const std::uint32_t v : border_vertices(unlocked.triangles)) outer_kept += outer_set.count(v);
  EXPECT_LT(outer_kept, outer_set.size());
  EXPECT_THROW((void)simplify_mesh(g.positions, g.triangles, free_borders, std::span(outer).first(3)), ProcessingError);
}

TEST(Simplify, WeldingLetsCollapsesCrossAttributeSeams) {
  // A grid whose four quadrants have their own copies of the vertices they share (as tiles
  // hold one vertex per source acquisition): seams hold edge collapses back, and the centre,
  // shared four ways, never moves. Welded, the grid simplifies further, and every corner is
  // the first vertex of its position.
  const int n = 40;
  Grid g = holed_grid(n);
  const auto id = [n](int i, int j) { return static_cast<std::uint32_t>(i * (n + 1) + j); };
  std::map<std::pair<std::uint32_t, int>, std::uint32_t> copy;  // (vertex, quadrant) -> its copy
  for (Triangle& t : g.triangles) {
    float cx = 0, cy = 0;
    for (const std::uint32_t v : t) {
      cx += g.positions[v].x / 3;
      cy += g.positions[v].y / 3;
    }
    const int quadrant = (cx > 0.25f * n ? 1 : 0) + (cy > 0.25f * n ? 2 : 0);
    if (quadrant == 0) continue;
    for (std::uint32_t& v : t) {
      const auto [it, added] = copy.try_emplace({v, quadrant}, static_cast<std::uint32_t>(g.positions.size()));
      if (added) g.positions.push_back(g.positions[v]);
      v = it->second;
    }
  }
  SimplifyParams p{.target_ratio = 0.02, .max_error_fraction = 0.05, .lock_border = false};
  const SimplifiedMesh seams = simplify_mesh(g.positions, g.triangles, p);
  p.weld = true;
  const SimplifiedMesh welded = simplify_mesh(g.positions, g.triangles, p);
  EXPECT_LT(welded.triangles.size(), seams.triangles.size());
  EXPECT_GT(welded.triangles.size(), 0u);
  for (const Triangle& t : welded.triangles) {
    for (const std::uint32_t v : t) EXPECT_LE(v, id(n, n)) << "a copy, not the first vertex of its position";
  }
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
