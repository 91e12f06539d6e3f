// SPDX-License-Identifier: MIT
// The crack count against hand-made tiles whose seams and cracks are known.
#include <gtest/gtest.h>

#include "tile_cracks.h"

namespace citymesh::tiles3d_detail {
namespace {

/// The unit square [x, x + 1] x [y, y + 1] as two triangles, counter-clockwise.
struct Square {
  std::vector<Vec3f> positions;
  std::vector<Triangle> triangles{{0, 1, 2}, {0, 2, 3}};
  Square(float x, float y) : positions{{x, y, 0}, {x + 1, y, 0}, {x + 1, y + 1, 0}, {x, y + 1, 0}} {}
};

// Two leaves side by side (x in [0, 1] and [1, 2]) sharing the edge x = 1; a parent above the
// first leaf only, and a root above everything.
struct TwoLeaves {
  TileCrackCounter counter;
  std::uint32_t root, parent, left, right;
  TwoLeaves() {
    root = counter.add_tile(TileCrackCounter::kNoParent);
    parent = counter.add_tile(root);
    left = counter.add_tile(parent);
    right = counter.add_tile(root);
    const Square a(0, 0), b(1, 0);
    counter.set_content(left, a.positions, a.triangles);
    counter.set_content(right, b.positions, b.triangles);
  }
  /// Gives back what set_content was given for the parent.
  void set_parent(std::vector<Vec3f> positions, std::vector<Triangle> triangles) {
    parent_content = {std::move(positions), std::move(triangles)};
    counter.set_content(parent, parent_content.positions, parent_content.triangles);
  }
  [[nodiscard]] TileContentSource reload() const {
    return [this](std::uint32_t tile) {
      EXPECT_EQ(tile, parent) << "only the parent lacks the seam";
      return parent_content;
    };
  }
  TileContent parent_content;
};

/// For tiles that must never be asked again.
TileContent no_reload(std::uint32_t tile) {
  ADD_FAILURE() << "tile " << tile << " asked again";
  return {};
}

TEST(TileCracks, AParentKeepingItsBorderHasNoCrack) {
  TwoLeaves t;
  const Square a(0, 0);
  t.set_parent(a.positions, a.triangles);
  const TileCracks c = t.counter.count(t.reload());
  EXPECT_EQ(c.seam_edges, 1u);
  EXPECT_DOUBLE_EQ(c.seam_length, 1.0);
  EXPECT_EQ(c.crack_edges, 0u);
  EXPECT_EQ(c.crack_length, 0.0);
  EXPECT_TRUE(c.by_tile.empty());
}

TEST(TileCracks, AParentWhoseBorderMovedCracksAlongTheWholeSeam) {
  TwoLeaves t;
  Square moved(0, 0);
  moved.positions[1].x = 0.9f;  // the corner (1, 0) pulled in: the seam x = 1 is gone
  t.set_parent(moved.positions, moved.triangles);
  const TileCracks c = t.counter.count(t.reload());
  EXPECT_EQ(c.crack_edges, 1u);
  EXPECT_DOUBLE_EQ(c.crack_length, 1.0);
  ASSERT_EQ(c.by_tile.size(), 1u);
  EXPECT_EQ(c.by_tile[0].first, t.parent);
}

TEST(TileCracks, ASeamInsideATileWhereThreeTrianglesMeetIsNoCrack) {
  TwoLeaves t;
  // The parent's square with a flap standing on the seam edge x = 1: that edge is no longer
  // open in the parent (two triangles use it), but the parent still covers it.
  Square a(0, 0);
  a.positions.push_back({1, 0.5f, 1});
  a.triangles.push_back({1, 2, 4});
  t.set_parent(a.positions, a.triangles);
  const TileCracks c = t.counter.count(t.reload());
  EXPECT_EQ(c.seam_edges, 1u);
  EXPECT_EQ(c.crack_length, 0.0);
}

TEST(TileCracks, ATileAboveBothLeavesAndATileWithoutContentNeedNoSeam) {
  TwoLeaves t;
  // The root holds one square over both leaves: the seam is inside it, no crack. The parent
  // has no content: nothing is drawn there.
  const Square whole(0, 0);
  t.counter.set_content(t.root, whole.positions, whole.triangles);
  const TileCracks c = t.counter.count(t.reload());
  EXPECT_EQ(c.seam_edges, 1u);
  EXPECT_EQ(c.crack_length, 0.0);
}

TEST(TileCracks, DuplicatedVerticesAreOneCornerAndHoleRimsAreNoSeams) {
  TileCrackCounter counter;
  const std::uint32_t root = counter.add_tile(TileCrackCounter::kNoParent);
  const std::uint32_t leaf = counter.add_tile(root);
  // The square with its diagonal's corners duplicated (as Draco splits a vertex between
  // two feature ids): still two triangles sharing one edge, four open edges.
  const std::vector<Vec3f> positions{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  const std::vector<Triangle> triangles{{0, 1, 2}, {3, 4, 5}};
  counter.set_content(leaf, positions, triangles);
  // A root that lost the square's border: no leaf beside it, so nothing to meet.
  const Square smaller(0.2f, 0.2f);
  counter.set_content(root, smaller.positions, smaller.triangles);
  const TileCracks c = counter.count(no_reload);
  EXPECT_EQ(c.seam_edges, 0u);
  EXPECT_EQ(c.crack_length, 0.0);
}

}  // namespace
}  // namespace citymesh::tiles3d_detail
