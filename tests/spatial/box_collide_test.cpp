// SPDX-License-Identifier: MIT
#include "citymesh/spatial/box_collide.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <mutex>
#include <random>
#include <utility>
#include <vector>

#include "citymesh/core/parallel.h"

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

std::vector<std::pair<std::uint32_t, std::uint32_t>> collide(const std::vector<Box3f>& a, const std::vector<Box3f>& b) {
  std::mutex m;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
  collide_boxes(a, b, [&](std::span<const BoxPair> batch) {
    std::lock_guard lock(m);
    for (const BoxPair& p : batch) pairs.emplace_back(p.a, p.b);
  });
  std::sort(pairs.begin(), pairs.end());
  return pairs;
}

TEST(BoxCollide, FindsExactlyTheOverlappingPairsOfBruteForce) {
  std::mt19937 rng(3);
  // Many small boxes and a few long thin ones, like triangles against empty-space tetrahedra.
  std::vector<Box3f> a = random_boxes(rng, 3000, 10, 0.6f);
  std::vector<Box3f> b = random_boxes(rng, 2000, 10, 0.6f);
  for (Box3f& box : random_boxes(rng, 50, 10, 1.0f)) {
    box.max.x += 8;
    b.push_back(box);
  }
  std::vector<std::pair<std::uint32_t, std::uint32_t>> expected;
  for (std::uint32_t i = 0; i < a.size(); ++i) {
    for (std::uint32_t j = 0; j < b.size(); ++j) {
      const Box3f &p = a[i], &q = b[j];
      if (p.min.x <= q.max.x && q.min.x <= p.max.x && p.min.y <= q.max.y && q.min.y <= p.max.y &&
          p.min.z <= q.max.z && q.min.z <= p.max.z) {
        expected.emplace_back(i, j);
      }
    }
  }
  ASSERT_GT(expected.size(), 1000u);
  EXPECT_EQ(collide(a, b), expected);
  ThreadLimit one(1);
  EXPECT_EQ(collide(a, b), expected);
}

TEST(BoxCollide, EmptySetsGiveNoPairs) {
  std::mt19937 rng(4);
  EXPECT_TRUE(collide({}, random_boxes(rng, 10, 5, 1)).empty());
  EXPECT_TRUE(collide(random_boxes(rng, 10, 5, 1), {}).empty());
}

}  // namespace
}  // namespace citymesh
