// SPDX-License-Identifier: MIT
#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "citymesh/spatial/kd_tree.h"

namespace citymesh {
namespace {

std::vector<Vec3f> random_points(std::size_t n, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-10.f, 10.f);
  std::vector<Vec3f> p(n);
  for (auto& v : p) v = {u(rng), u(rng), u(rng) * 0.2f};
  return p;
}

float distance2(const Vec3f& a, const Vec3f& b) { return dot(a - b, a - b); }

TEST(PointKdTree, RadiusSearchEqualsBruteForce) {
  const auto points = random_points(5000, 1);
  PointKdTree tree(points);
  const auto queries = random_points(200, 2);
  std::vector<std::uint32_t> found;
  for (const Vec3f& q : queries) {
    for (float radius : {0.1f, 0.5f, 2.0f}) {
      tree.radius_search(q, radius, found);
      std::vector<std::uint32_t> expected;
      for (std::uint32_t i = 0; i < points.size(); ++i) {
        if (distance2(points[i], q) <= radius * radius) expected.push_back(i);
      }
      ASSERT_EQ(found, expected);
    }
  }
}

TEST(PointKdTree, NearestEqualsBruteForce) {
  const auto points = random_points(2000, 3);
  PointKdTree tree(points);
  for (const Vec3f& q : random_points(100, 4)) {
    std::vector<std::uint32_t> order(points.size());
    for (std::uint32_t i = 0; i < order.size(); ++i) order[i] = i;
    std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
      return std::make_pair(distance2(points[a], q), a) < std::make_pair(distance2(points[b], q), b);
    });
    order.resize(8);
    EXPECT_EQ(tree.nearest(q, 8), order);
  }
}

TEST(PointKdTree, EmptyTreeFindsNothing) {
  PointKdTree tree({});
  std::vector<std::uint32_t> found{1, 2};
  tree.radius_search({0, 0, 0}, 1.0f, found);
  EXPECT_TRUE(found.empty());
  EXPECT_TRUE(tree.nearest({0, 0, 0}, 3).empty());
}

}  // namespace
}  // namespace citymesh
