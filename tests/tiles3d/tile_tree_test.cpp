// SPDX-License-Identifier: MIT
// The level-of-detail tree: every triangle in one leaf, parents after their children, and no
// parent that merely repeats its only child.
#include "citymesh/tiles3d/tile_tree.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <mutex>
#include <set>
#include <string>

#include "citymesh/core/error.h"
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

  /// A wavy n x n grid of 1 m cells at x0: every edge collapse moves the surface.
  void add_wavy_grid(TileKey key, float x0, int n) {
    const auto base = static_cast<std::uint32_t>(vertices.positions.size());
    for (int i = 0; i <= n; ++i) {
      for (int j = 0; j <= n; ++j)
        add_vertex({x0 + float(i), float(j), 0.4f * std::sin(1.3f * float(i)) * std::cos(0.9f * float(j))});
    }
    for (const Triangle& t : test::grid_triangles(n)) add({t[0] + base, t[1] + base, t[2] + base}, key);
  }

  /// An n x n grid of 1 m cells at x0 keeping every other row of cells: strips one cell wide,
  /// every vertex on a border, which locked borders keep in place.
  void add_strips(TileKey key, float x0, int n) {
    const auto base = static_cast<std::uint32_t>(vertices.positions.size());
    for (int i = 0; i <= n; ++i) {
      for (int j = 0; j <= n; ++j) add_vertex({x0 + float(i), float(j), 0});
    }
    for (const Triangle& t : test::grid_triangles(n, [](int i, int) { return i % 2 == 0; })) {
      add({t[0] + base, t[1] + base, t[2] + base}, key);
    }
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

/// A tile as a reader of the tileset sees it: level, its triangles (global vertices, in
/// order), error, box and children by name. Node numbers are left out: they follow the order
/// in which the tree was built.
struct TileView {
  std::vector<Triangle> triangles;
  double geometric_error = 0;
  Vec3d box_min, box_max;
  std::vector<std::string> children;
  bool operator==(const TileView&) const = default;
};

std::vector<Triangle> global_triangles(const TileMesh& m) {
  std::vector<Triangle> out;
  const auto global = [&](std::uint32_t v) { return static_cast<std::uint32_t>(m.keys[v].vertex); };
  for (const Triangle& t : m.triangles) out.push_back({global(t[0]), global(t[1]), global(t[2])});
  return out;
}

std::map<std::string, TileView> view_of(const TileTree& tree) {
  std::map<std::string, TileView> tiles;
  for (const TileNode& node : tree.nodes) {
    TileView& v = tiles[node.name()];
    v.triangles = global_triangles(node.mesh);
    v.geometric_error = node.geometric_error;
    v.box_min = node.box.min;
    v.box_max = node.box.max;
    for (const std::uint32_t c : node.children) v.children.push_back(tree.nodes[c].name());
  }
  return tiles;
}

/// 7 x 5 leaves with two missing, of flat grids (which simplify) and loose triangles (which do
/// not), plus a leaf far away that meets the others only near the root.
Input scattered_leaves() {
  Input in;
  for (int i = 0; i < 7; ++i) {
    for (int j = 0; j < 5; ++j) {
      if ((i == 2 && j == 3) || (i == 5 && j == 0)) continue;
      const float x0 = 40.0f * float(5 * i + j);
      if ((i + j) % 3 == 0) {
        in.add_loose_triangles({i - 3, j - 2}, x0, 12);
      } else {
        in.add_flat_grid({i - 3, j - 2}, x0, 8);
      }
    }
  }
  in.add_flat_grid({90, -40}, 9000, 8);
  return in;
}

TEST(TileTree, DepthFirstCellsGiveTheSameTilesAsLevelByLevel) {
  const Input in = scattered_leaves();
  TileTreeParams level_by_level;
  level_by_level.depth_first_cells = std::numeric_limits<std::size_t>::max();
  const TileTree reference = build_tile_tree(in.vertices, in.triangles, in.keys, level_by_level);
  expect_well_formed(reference, in);
  const auto expected = view_of(reference);
  for (const std::size_t cells : {std::size_t{1}, std::size_t{2}, std::size_t{4}, std::size_t{16}}) {
    TileTreeParams params;
    params.depth_first_cells = cells;
    const TileTree tree = build_tile_tree(in.vertices, in.triangles, in.keys, params);
    expect_well_formed(tree, in);
    EXPECT_EQ(view_of(tree), expected) << "depth_first_cells " << cells;
    EXPECT_EQ(tree.root().name(), reference.root().name());
  }
}

/// Each leaf's mesh as build_tile_tree(vertices, ...) makes it: its triangles' vertices
/// ascending, keyed by their index in the buffer.
LeafSource leaf_source(const Input& in) {
  return [&in](const TileKey& key) {
    std::vector<Triangle> own;
    std::vector<std::uint32_t> used;
    for (std::size_t t = 0; t < in.triangles.size(); ++t) {
      if (in.keys[t] != key) continue;
      own.push_back(in.triangles[t]);
      used.insert(used.end(), in.triangles[t].begin(), in.triangles[t].end());
    }
    std::sort(used.begin(), used.end());
    used.erase(std::unique(used.begin(), used.end()), used.end());
    TileMesh m;
    for (const std::uint32_t v : used) {
      m.keys.push_back({v, in.vertices.feature_ids[v]});
      m.positions.push_back(in.vertices.positions[v]);
    }
    const auto local = [&](std::uint32_t v) {
      return static_cast<std::uint32_t>(std::lower_bound(used.begin(), used.end(), v) - used.begin());
    };
    for (const Triangle& t : own) m.triangles.push_back({local(t[0]), local(t[1]), local(t[2])});
    return m;
  };
}

TEST(TileTree, CellsBuiltApartInAnyOrderAndFinishedGiveTheTreeOfOneBuild) {
  const Input in = scattered_leaves();
  TileTreeParams params;
  params.depth_first_cells = 4;
  const TileTree reference = build_tile_tree(in.vertices, in.triangles, in.keys, params);
  const auto expected = view_of(reference);
  std::vector<TileKey> leaves(in.keys.begin(), in.keys.end());
  std::sort(leaves.begin(), leaves.end());
  leaves.erase(std::unique(leaves.begin(), leaves.end()), leaves.end());

  // Every tile as a sink gets it, whichever build (a cell's or the finishing one) hands it over.
  std::mutex mutex;
  std::map<std::string, std::vector<Triangle>> handed;
  const TileNodeSink sink = [&](const TileNode& node) {
    const std::lock_guard lock(mutex);
    EXPECT_TRUE(handed.emplace(node.name(), global_triangles(node.mesh)).second) << node.name() << " twice";
  };
  const LeafSource source = leaf_source(in);
  const TileTreeBuild build(leaves, source, params, sink);
  ASSERT_GE(build.cell_count(), 4u);
  std::vector<TileSubtree> cells(build.cell_count());
  std::size_t cell_leaves = 0;
  for (std::size_t c = cells.size(); c-- > 0;) {  // backwards, each from a build of its own
    const TileTreeBuild apart(leaves, source, params, sink);
    cells[c] = apart.build_cell(c);
    const std::vector<TileKey> own = build.cell_leaves(c);
    cell_leaves += own.size();
    EXPECT_TRUE(std::is_sorted(own.begin(), own.end()));
    const TileNode& open = cells[c].nodes.at(cells[c].open);
    EXPECT_FALSE(open.mesh.triangles.empty()) << "cell " << c << ": the open node's mesh was released";
    EXPECT_FALSE(handed.contains(open.name())) << "cell " << c << ": its open node was handed over";
  }
  EXPECT_EQ(cell_leaves, leaves.size()) << "every leaf in one cell";
  const TileTree tree = build.finish(std::move(cells));

  ASSERT_EQ(tree.nodes.size(), reference.nodes.size());
  for (std::size_t n = 0; n < tree.nodes.size(); ++n) {
    const TileNode& node = tree.nodes[n];
    EXPECT_EQ(node.name(), reference.nodes[n].name()) << "node " << n << ": another order";
    const TileView& want = expected.at(node.name());
    EXPECT_EQ(handed.at(node.name()), want.triangles) << node.name();
    EXPECT_EQ(node.geometric_error, want.geometric_error) << node.name();
    EXPECT_EQ(node.box.min, want.box_min) << node.name();
    EXPECT_EQ(node.box.max, want.box_max) << node.name();
    std::vector<std::string> children;
    for (const std::uint32_t c : node.children) children.push_back(tree.nodes[c].name());
    EXPECT_EQ(children, want.children) << node.name();
  }
  EXPECT_EQ(handed.size(), reference.nodes.size());
  EXPECT_THROW((void)build.finish({}), ProcessingError) << "subtrees missing";
}

TEST(TileTree, TheSinkGetsEveryTileOnceChildrenFirstAndItsMeshIsThenReleased) {
  const Input in = scattered_leaves();
  const TileTree kept = build_tile_tree(in.vertices, in.triangles, in.keys, {});
  std::mutex mutex;
  std::map<std::string, std::vector<Triangle>> handed;
  std::set<std::string> order_violations;
  std::map<std::string, std::vector<std::string>> children_of;
  for (const TileNode& node : kept.nodes) {
    for (const std::uint32_t c : node.children) children_of[node.name()].push_back(kept.nodes[c].name());
  }
  TileTreeParams params;
  params.depth_first_cells = 2;
  const TileTree tree = build_tile_tree(in.vertices, in.triangles, in.keys, params, [&](const TileNode& node) {
    const std::lock_guard lock(mutex);
    for (const std::string& child : children_of[node.name()]) {
      if (!handed.contains(child)) order_violations.insert(node.name());
    }
    EXPECT_TRUE(handed.emplace(node.name(), global_triangles(node.mesh)).second) << node.name() << " twice";
  });
  EXPECT_TRUE(order_violations.empty());
  ASSERT_EQ(handed.size(), kept.nodes.size());
  const auto expected = view_of(kept);
  for (const TileNode& node : tree.nodes) {
    EXPECT_TRUE(node.mesh.triangles.empty() && node.mesh.keys.empty()) << node.name();
    EXPECT_EQ(handed.at(node.name()), expected.at(node.name()).triangles) << node.name();
    EXPECT_EQ(node.triangle_count, expected.at(node.name()).triangles.size()) << node.name();
  }
}

TEST(TileTree, AParentThatLockedBordersKeepLargeIsCappedWithItsBordersFree) {
  // Four leaves of strips (256 triangles each): with every vertex on a locked border the root
  // keeps all 1024; past a cap of 200 it is simplified again with its borders free.
  Input in;
  for (int i = 0; i < 2; ++i) {
    for (int j = 0; j < 2; ++j) in.add_strips({i, j}, 40.0f * float(2 * i + j), 16);
  }
  TileTreeParams uncapped;
  uncapped.max_parent_triangles = std::numeric_limits<std::size_t>::max();
  const TileTree locked = build_tile_tree(in.vertices, in.triangles, in.keys, uncapped);
  expect_well_formed(locked, in);
  EXPECT_EQ(locked.root().level, 1);
  EXPECT_EQ(triangles_of(locked, static_cast<std::uint32_t>(locked.nodes.size() - 1)), 1024u);

  TileTreeParams capped;
  capped.max_parent_triangles = 200;
  const TileTree tree = build_tile_tree(in.vertices, in.triangles, in.keys, capped);
  expect_well_formed(tree, in);
  EXPECT_EQ(tree.root().level, 1);
  EXPECT_LE(triangles_of(tree, static_cast<std::uint32_t>(tree.nodes.size() - 1)), 200u);
  EXPECT_GT(triangles_of(tree, static_cast<std::uint32_t>(tree.nodes.size() - 1)), 0u);
  // Leaves are never capped.
  for (const TileNode& node : tree.nodes) {
    if (node.level == 0) {
      EXPECT_EQ(node.mesh.triangles.size(), 256u);
    }
  }
}

TEST(TileTree, ACappedParentThatEdgeCollapsesCannotTakeIsClusteredDownToTheCap) {
  // Wavy grids at a tolerance no edge collapse meets, borders locked or not: clustering
  // (whatever the error, the cap first) brings the parent to the cap.
  Input in;
  for (int i = 0; i < 2; ++i) {
    for (int j = 0; j < 2; ++j) in.add_wavy_grid({i, j}, 30.0f * float(2 * i + j), 20);
  }
  TileTreeParams capped;
  capped.simplify.max_error_fraction = 1e-9;
  capped.max_parent_triangles = 600;  // of the 3200 the four leaves hold
  const TileTree tree = build_tile_tree(in.vertices, in.triangles, in.keys, capped);
  expect_well_formed(tree, in);
  EXPECT_EQ(tree.root().level, 1);
  const std::size_t root = triangles_of(tree, static_cast<std::uint32_t>(tree.nodes.size() - 1));
  EXPECT_LE(root, 600u);
  EXPECT_GT(root, 0u);
  EXPECT_GT(tree.root().geometric_error, 0.0);
}

}  // namespace
}  // namespace citymesh
