// SPDX-License-Identifier: MIT
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "citymesh/spatial/ray_scene.h"

namespace citymesh {
namespace {

/// Möller–Trumbore in double: the reference the Embree wrapper is checked against.
std::optional<double> brute_hit(const Vec3d& o, const Vec3d& d, const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  const Vec3d e1 = b - a, e2 = c - a, p = cross(d, e2);
  const double det = dot(e1, p);
  if (std::abs(det) < 1e-12) return std::nullopt;
  const Vec3d s = o - a;
  const double u = dot(s, p) / det;
  const Vec3d q = cross(s, e1);
  const double v = dot(d, q) / det;
  const double t = dot(e2, q) / det;
  if (u < 0 || v < 0 || u + v > 1 || t < 0) return std::nullopt;
  return t;
}

TEST(RayScene, ClosestHitEqualsBruteForce) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-5.f, 5.f);
  std::vector<Vec3f> vertices;
  std::vector<Triangle> triangles;
  for (std::uint32_t t = 0; t < 300; ++t) {
    const Vec3f centre{u(rng), u(rng), u(rng)};
    for (int k = 0; k < 3; ++k) vertices.push_back(centre + Vec3f{u(rng), u(rng), u(rng)} * 0.2f);
    triangles.push_back({3 * t, 3 * t + 1, 3 * t + 2});
  }
  RayScene scene(vertices, triangles);
  int hits = 0;
  for (int r = 0; r < 2000; ++r) {
    const Vec3f origin{u(rng), u(rng), u(rng)};
    Vec3f dir{u(rng), u(rng), u(rng)};
    dir = dir / norm(dir);
    std::optional<double> best;
    std::uint32_t best_t = 0;
    for (std::uint32_t t = 0; t < triangles.size(); ++t) {
      auto h = brute_hit(Vec3d(origin), Vec3d(dir), Vec3d(vertices[triangles[t][0]]), Vec3d(vertices[triangles[t][1]]),
                         Vec3d(vertices[triangles[t][2]]));
      if (h && *h <= 20.0 && (!best || *h < *best)) {
        best = h;
        best_t = t;
      }
    }
    const RayHit hit = scene.intersect(origin, dir, 20.0f);
    ASSERT_EQ(hit.hit, best.has_value()) << "ray " << r;
    if (best) {
      ++hits;
      EXPECT_NEAR(hit.distance, *best, 1e-4);
      EXPECT_EQ(hit.triangle, best_t);
    }
  }
  EXPECT_GT(hits, 50);  // the test must actually exercise hits
}

TEST(RayScene, RespectsMaximumDistanceAndMissesEmptySpace) {
  const std::vector<Vec3f> v{{-1, -1, 5}, {1, -1, 5}, {0, 1, 5}};
  const std::vector<Triangle> t{{0, 1, 2}};
  RayScene scene(v, t);
  EXPECT_TRUE(scene.intersect({0, 0, 0}, {0, 0, 1}, 10).hit);
  EXPECT_NEAR(scene.intersect({0, 0, 0}, {0, 0, 1}, 10).distance, 5.0f, 1e-6);
  EXPECT_FALSE(scene.intersect({0, 0, 0}, {0, 0, 1}, 4).hit);
  EXPECT_FALSE(scene.intersect({0, 0, 0}, {0, 0, -1}, 10).hit);
}

}  // namespace
}  // namespace citymesh
