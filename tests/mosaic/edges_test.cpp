// SPDX-License-Identifier: MIT
#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "citymesh/mosaic/edges.h"

namespace citymesh {
namespace {

/// The definition: every edge of every wanted triangle, sorted by (lo, hi, triangle).
std::vector<EdgeUse> sorted_uses(std::span<const Triangle> triangles, std::span<const std::uint8_t> subset) {
  std::vector<EdgeUse> uses;
  for (std::uint32_t t = 0; t < triangles.size(); ++t) {
    if (!subset.empty() && subset[t] == 0) continue;
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t u = triangles[t][k], v = triangles[t][(k + 1) % 3];
      uses.push_back({std::min(u, v), std::max(u, v), t});
    }
  }
  std::sort(uses.begin(), uses.end());
  return uses;
}

TEST(EdgeUses, EqualTheSortedUsesOnRandomMeshesAndFans) {
  std::mt19937 rng(11);
  for (int scene = 0; scene < 20; ++scene) {
    std::uniform_int_distribution<std::uint32_t> vertex(0, scene % 2 == 0 ? 40 : 4000);
    std::vector<Triangle> triangles;
    for (int t = 0; t < 3000; ++t) triangles.push_back({vertex(rng), vertex(rng), vertex(rng)});
    // A fan of 500 triangles around vertex 7: one vertex with many uses.
    for (std::uint32_t k = 0; k < 500; ++k) triangles.push_back({7, 5000 + k, 5001 + k});
    std::shuffle(triangles.begin(), triangles.end(), rng);
    std::vector<std::uint8_t> subset(triangles.size());
    for (auto& s : subset) s = static_cast<std::uint8_t>(rng() % 3 != 0);
    EXPECT_EQ(edge_uses(triangles), sorted_uses(triangles, {})) << "scene " << scene;
    EXPECT_EQ(edge_uses(triangles, subset), sorted_uses(triangles, subset)) << "scene " << scene;
  }
  EXPECT_TRUE(edge_uses(std::vector<Triangle>{}).empty());
}

}  // namespace
}  // namespace citymesh
