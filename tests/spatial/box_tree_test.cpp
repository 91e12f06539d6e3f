// SPDX-License-Identifier: MIT
#include "citymesh/spatial/box_tree.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <random>
#include <vector>

namespace citymesh {
namespace {

std::vector<Box3f> random_boxes(std::mt19937& rng, std::size_t n, float world, float max_side) {
  std::uniform_real_distribution<float> pos(0, world), side(0.01f, max_side);
  std::vector<Box3f> boxes(n);
  for (Box3f& b : boxes) {
    b.min = {pos(rng), pos(rng), pos(rng)};
    b.max = b.min + Vec3f{side(rng), side(rng), side(rng)};
  }
  return boxes;
}

bool meet(const Box3f& p, const Box3f& q) {
  return p.min.x <= q.max.x && q.min.x <= p.max.x && p.min.y <= q.max.y && q.min.y <= p.max.y &&
         p.min.z <= q.max.z && q.min.z <= p.max.z;
}

std::vector<std::uint32_t> brute_force(const std::vector<Box3f>& boxes, const Box3f& query) {
  std::vector<std::uint32_t> out;
  for (std::uint32_t i = 0; i < boxes.size(); ++i) {
    if (meet(boxes[i], query)) out.push_back(i);
  }
  return out;
}

/// Small boxes and a few long thin ones, like triangles and empty-space tetrahedra, far from
/// the origin like city coordinates in a tile frame.
std::vector<Box3f> scene_boxes(std::mt19937& rng) {
  std::vector<Box3f> boxes = random_boxes(rng, 3000, 10, 0.6f);
  for (Box3f& box : random_boxes(rng, 50, 10, 1.0f)) {
    box.max.x += 8;
    boxes.push_back(box);
  }
  for (Box3f& b : boxes) {
    b.min = b.min + Vec3f{500, -300, 40};
    b.max = b.max + Vec3f{500, -300, 40};
  }
  return boxes;
}

TEST(BoxTree, OverlappingEqualsBruteForce) {
  std::mt19937 rng(3);
  const std::vector<Box3f> boxes = scene_boxes(rng);
  const BoxTree tree(boxes);
  std::size_t found = 0;
  std::vector<std::uint32_t> out;
  for (Box3f q : random_boxes(rng, 500, 10, 0.8f)) {
    q.min = q.min + Vec3f{500, -300, 40};
    q.max = q.max + Vec3f{500, -300, 40};
    tree.overlapping(q, out);
    std::sort(out.begin(), out.end());
    EXPECT_EQ(out, brute_force(boxes, q));
    found += out.size();
  }
  EXPECT_GT(found, 300u);
}

TEST(BoxTree, ContainingFindsBoxesWhosePointsAreOnTheirFaces) {
  std::mt19937 rng(5);
  const std::vector<Box3f> boxes = scene_boxes(rng);
  const BoxTree tree(boxes);
  std::vector<std::uint32_t> out;
  // Each box's own corners lie on its closed boundary: it must be found.
  for (std::uint32_t i = 0; i < boxes.size(); i += 7) {
    for (const Vec3f& p : {boxes[i].min, boxes[i].max, Vec3f{boxes[i].min.x, boxes[i].max.y, boxes[i].min.z}}) {
      tree.containing(p, out);
      std::sort(out.begin(), out.end());
      EXPECT_EQ(out, brute_force(boxes, {p, p}));
      EXPECT_TRUE(std::binary_search(out.begin(), out.end(), i)) << i;
    }
  }
}

TEST(BoxTree, CoincidentBoxesAreAllFoundAndOrderedOnce) {
  // Every centre on one Morton cell (a flat extent) and more boxes than one node holds.
  std::vector<Box3f> boxes(100, Box3f{{1, 2, 3}, {1, 2.5f, 3}});
  boxes[37] = {{0, 0, 0}, {0.5f, 0.5f, 0.5f}};
  const BoxTree tree(boxes);
  std::vector<std::uint32_t> out;
  tree.containing({1, 2.2f, 3}, out);
  std::sort(out.begin(), out.end());
  EXPECT_EQ(out, brute_force(boxes, {{1, 2.2f, 3}, {1, 2.2f, 3}}));
  EXPECT_EQ(out.size(), 99u);
  std::vector<std::uint32_t> order(tree.storage_order().begin(), tree.storage_order().end());
  std::sort(order.begin(), order.end());
  for (std::uint32_t i = 0; i < order.size(); ++i) EXPECT_EQ(order[i], i);
  EXPECT_EQ(order.size(), boxes.size());
}

TEST(BoxTree, ContainingEachGivesEachPointsOwnQueryInItsOrder) {
  std::mt19937 rng(9);
  const std::vector<Box3f> boxes = scene_boxes(rng);
  const BoxTree tree(boxes);
  // Packets as the consistency search makes them (centres of neighbouring boxes in the tree's
  // order), then points anywhere, in packets of every size up to the largest.
  std::vector<Vec3f> points;
  for (const std::uint32_t i : tree.storage_order()) points.push_back((boxes[i].min + boxes[i].max) * 0.5f);
  std::uniform_real_distribution<float> u(0, 10);
  for (int k = 0; k < 400; ++k) points.push_back(Vec3f{u(rng), u(rng), u(rng)} + Vec3f{500, -300, 40});
  std::array<std::vector<std::uint32_t>, BoxTree::kPacket> each;
  std::vector<std::uint32_t> one;
  std::size_t found = 0, size = 1;
  for (std::size_t i = 0; i < points.size(); i += size, size = size % BoxTree::kPacket + 1) {
    const std::size_t n = std::min(size, points.size() - i);
    const std::span<const Vec3f> packet(points.data() + i, n);
    tree.containing_each(packet, each);
    for (std::size_t k = 0; k < n; ++k) {
      tree.containing(packet[k], one);
      ASSERT_EQ(each[k], one) << "point " << i + k;
      found += one.size();
    }
  }
  EXPECT_GT(found, 3000u);
}

TEST(BoxTree, EmptySetFindsNothing) {
  const BoxTree tree({});
  std::vector<std::uint32_t> out{1, 2};
  tree.containing({0, 0, 0}, out);
  EXPECT_TRUE(out.empty());
}

}  // namespace
}  // namespace citymesh
