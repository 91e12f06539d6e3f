// SPDX-License-Identifier: MIT
// The level-of-detail tree: every triangle in one leaf, parents after their children, and no
// parent that merely repeats its only child.
#include <gtest/gtest.h>

#include <set>

#include "citymesh/tiles3d/tile_tree.h"
#include "grid_triangles.h"

namespace citymesh {
namespace {

/// Leaves' triangles in global vertex indices, with their leaf keys.
struct Input {
  TilesetVertices vertices;
  std::vector<Triangle> triangles;
  std::vector<TileKey> keys;

  /// A flat n x n grid of 1 m cells at x0 (the simplifier collapses its interior).
  void add_flat_grid(TileKey key, float x0, int n) {
    const auto base = static_cast<std::uint32_t>(vertices.positions.size());
    for (int i = 0; i <= n; ++i) {
      for (int j = 0; j <= n; ++j) add_vertex({x0 + float(i), float(j), 0});
    }
    for (const Triangle& t : test::grid_triangles(n)) add({t[0] + base, t[1] + base, t[2] + base}, key);
  }

  /// `count` separate triangles at x0: every vertex is on a border, which the simplifier
  /// keeps in place, so nothing can be removed.
  void add_loose_triangles(TileKey key, float x0, int count) {
    for (int k = 0; k < count; ++k) {
      const auto base = static_cast<std::uint32_t>(vertices.positions.size());
      add_vertex({x0 + 2.0f * float(k), 0, 0});
      add_vertex({x0 + 2.0f * float(k) + 1, 0, 0});
      add_vertex({x0 + 2.0f * float(k), 1, 0.5f});
      add({base, base + 1, base + 2}, key);
    }
  }

 private:
  void add_vertex(const Vec3f& p) {
    vertices.positions.push_back(p);
    vertices.feature_ids.push_back(0);
  }
  void add(const Triangle& t, TileKey key) {
    triangles.push_back(t);
    keys.push_back(key);
  }
};

std::size_t triangles_of(const TileTree& tree, std::uint32_t n) { return tree.nodes[n].mesh.triangles.size(); }

/// What holds for any tree: children before parents, the root last and reached from every
/// node, each input triangle in exactly one leaf, and a parent of one child keeping at most
/// half of that child's triangles.
void expect_well_formed(const TileTree& tree, const Input& in) {
  ASSERT_FALSE(tree.nodes.empty());
  std::vector<int> parents(tree.nodes.size(), 0);
  std::size_t leaf_triangles = 0;
  for (std::uint32_t n = 0; n < tree.nodes.size(); ++n) {
    const TileNode& node = tree.nodes[n];
    for (const std::uint32_t c : node.children) {
      ASSERT_LT(c, n);
      ++parents[c];
      EXPECT_LT(tree.nodes[c].level, node.level);
    }
    if (node.children.empty()) leaf_triangles += node.mesh.triangles.size();
    if (node.children.size() == 1) {
      EXPECT_LE(2 * triangles_of(tree, n), triangles_of(tree, node.children[0]));
    }
  }
  for (std::size_t n = 0; n + 1 < tree.nodes.size(); ++n) EXPECT_EQ(parents[n], 1) << "node " << n;
  EXPECT_EQ(parents.back(), 0);
  EXPECT_EQ(leaf_triangles, in.triangles.size());
}

TEST(TileTree, APassThatCannotSimplifyIsCarriedUpInsteadOfRepeated) {
  // Two leaves 64 tiles apart: their keys meet only at level 7. Neither simplifies (loose
  // triangles), so the root's children are the leaves themselves, not chains of copies.
  Input in;
  in.add_loose_triangles({0, 0}, 0, 40);
  in.add_loose_triangles({64, 0}, 3200, 40);
  const TileTree tree = build_tile_tree(in.vertices, in.triangles, in.keys, {});
  expect_well_formed(tree, in);
  ASSERT_EQ(tree.nodes.size(), 3u);
  EXPECT_EQ(tree.root().level, 7);
  EXPECT_EQ(tree.root().children, (std::vector<std::uint32_t>{0, 1}));
}

TEST(TileTree, AnIsolatedPassThatSimplifiesKeepsItsCoarserLevels) {
  // The flat grid alone simplifies to under half at least once before meeting the other leaf:
  // that single-child parent is a real coarser level and stays.
  Input in;
  in.add_flat_grid({0, 0}, 0, 30);
  in.add_loose_triangles({64, 0}, 3200, 40);
  const TileTree tree = build_tile_tree(in.vertices, in.triangles, in.keys, {});
  expect_well_formed(tree, in);
  std::size_t single_child_parents = 0;
  for (const TileNode& node : tree.nodes) single_child_parents += node.children.size() == 1 ? 1 : 0;
  EXPECT_GE(single_child_parents, 1u);
  EXPECT_EQ(tree.root().level, 7);
}

TEST(TileTree, NeighbouringLeavesShareParentsLevelByLevel) {
  // A 4 x 4 block of leaves: four parents at level 1, the root at level 2.
  Input in;
  for (int i = 0; i < 4; ++i) {
    for (int j = 0; j < 4; ++j) in.add_flat_grid({i, j}, 40.0f * float(4 * i + j), 6);
  }
  const TileTree tree = build_tile_tree(in.vertices, in.triangles, in.keys, {});
  expect_well_formed(tree, in);
  EXPECT_EQ(tree.nodes.size(), 16u + 4u + 1u);
  EXPECT_EQ(tree.root().level, 2);
  EXPECT_EQ(tree.root().children.size(), 4u);
}

}  // namespace
}  // namespace citymesh
