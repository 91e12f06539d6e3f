// SPDX-License-Identifier: MIT
// MeshProximity's queries against a pass over every triangle.
#include "citymesh/mosaic/proximity.h"

#include <gtest/gtest.h>

#include <random>

#include "citymesh/core/geometry.h"

namespace citymesh {
namespace {

/// Small triangles scattered in a 4 m cube, some flat on an axis.
Mesh random_mesh(std::mt19937& rng, std::size_t triangles) {
  std::uniform_real_distribution<float> where(0.f, 4.f), size(-0.3f, 0.3f);
  Mesh m;
  for (std::size_t t = 0; t < triangles; ++t) {
    const Vec3f a{where(rng), where(rng), where(rng)};
    const auto base = static_cast<std::uint32_t>(m.positions.size());
    m.positions.push_back(a);
    m.positions.push_back(a + Vec3f{size(rng), size(rng), t % 4 == 0 ? 0.f : size(rng)});
    m.positions.push_back(a + Vec3f{size(rng), size(rng), size(rng)});
    m.triangles.push_back({base, base + 1, base + 2});
  }
  return m;
}

bool brute_any_within(const Mesh& m, const Vec3d& p, double reach) {
  for (std::size_t t = 0; t < m.triangle_count(); ++t) {
    if (point_triangle_distance_sq(p, m.corners(t)) <= reach * reach) return true;
  }
  return false;
}

TEST(MeshProximity, AnyWithinEachAnswersLikeAPassOverEveryTriangle) {
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> where(-0.5, 4.5);
  const Mesh m = random_mesh(rng, 300);
  const MeshProximity near(m, 0.2);
  std::size_t yes = 0, asked = 0;
  for (std::size_t count : {0u, 1u, 7u, 8u, 9u, 23u, 200u}) {
    std::vector<Vec3d> points;
    for (std::size_t i = 0; i < count; ++i) points.push_back({where(rng), where(rng), where(rng)});
    for (const double reach : {0.05, 0.2}) {
      std::vector<std::uint8_t> within(count, 7);
      near.any_within_each(points, reach, within);
      for (std::size_t i = 0; i < count; ++i) {
        const bool expected = brute_any_within(m, points[i], reach);
        ASSERT_EQ(within[i], expected ? 1 : 0) << "point " << i << " of " << count << ", reach " << reach;
        ASSERT_EQ(near.any_within(points[i], reach), expected);
        yes += expected ? 1 : 0;
        ++asked;
      }
    }
  }
  EXPECT_GT(yes, asked / 10);
  EXPECT_LT(yes, asked);
}

}  // namespace
}  // namespace citymesh
