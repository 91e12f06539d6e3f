// SPDX-License-Identifier: MIT
// The empty spaces' slab boxes against the box of the six points that bound each slab.
#include <gtest/gtest.h>

#include <random>

#include "frames.h"

namespace citymesh::change_detail {
namespace {

/// The reference: the box of the two cross-sections' six corners, padded as every frame box.
Box3f six_point_box(const TetrahedronCorners& q, int k, int n) {
  const double s0 = double(k) / n, s1 = double(k + 1) / n;
  Box3d b;
  for (std::size_t i = 1; i < 4; ++i) {
    b.extend(q[0] + (q[i] - q[0]) * s0);
    b.extend(q[0] + (q[i] - q[0]) * s1);
  }
  const double pad = 1e-5 + 1e-6 * std::max({std::abs(b.min.x), std::abs(b.min.y), std::abs(b.min.z),
                                             std::abs(b.max.x), std::abs(b.max.y), std::abs(b.max.z)});
  b = b.grown(pad);
  return {Vec3f(b.min), Vec3f(b.max)};
}

TEST(EmptySpaceSlabs, EqualTheSixPointBoxToTheBit) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> coordinate(-80.0, 80.0), jitter(-0.5, 0.5);
  for (int trial = 0; trial < 2000; ++trial) {
    const Vec3d viewpoint{coordinate(rng), coordinate(rng), 2.0 + jitter(rng)};
    const Vec3d corner{coordinate(rng), coordinate(rng), coordinate(rng) * 0.2};
    // Mostly small triangles far from the viewpoint, as scanned; some flat on an axis.
    const TetrahedronCorners q{viewpoint, corner, corner + Vec3d{jitter(rng), jitter(rng), trial % 5 == 0 ? 0 : jitter(rng)},
                               corner + Vec3d{jitter(rng), trial % 7 == 0 ? 0 : jitter(rng), jitter(rng)}};
    const EmptySpaceSlabs slabs(q);
    const int n = slab_count(q, 0.5);
    for (int k = 0; k < n; ++k) {
      const Box3f expected = six_point_box(q, k, n), got = slabs.slab(k, n);
      for (int a = 0; a < 3; ++a) {
        ASSERT_EQ(got.min[a], expected.min[a]) << "trial " << trial << " slab " << k << " of " << n;
        ASSERT_EQ(got.max[a], expected.max[a]) << "trial " << trial << " slab " << k << " of " << n;
      }
    }
  }
}

TEST(EmptySpaceSlabs, TheBoxOfAStretchHoldsEachOfItsSlabsBoxesToTheBit) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> coordinate(-3000.0, 3000.0), jitter(-0.5, 0.5);
  for (int trial = 0; trial < 2000; ++trial) {
    const Vec3d viewpoint{coordinate(rng), coordinate(rng), 2.0 + jitter(rng)};
    const Vec3d corner = viewpoint + Vec3d{jitter(rng) * 80, jitter(rng) * 80, jitter(rng) * 30};
    const TetrahedronCorners q{viewpoint, corner, corner + Vec3d{jitter(rng), jitter(rng), jitter(rng)},
                               corner + Vec3d{jitter(rng), jitter(rng), jitter(rng)}};
    const EmptySpaceSlabs slabs(q);
    const int n = slab_count(q, 0.5);
    std::uniform_int_distribution<int> pick(0, n - 1);
    const int first = pick(rng), last = std::min(n, first + 1 + pick(rng) % 9);
    const Box3f stretch = slabs.between(double(first) / n, double(last) / n);
    for (int k = first; k < last; ++k) {
      const Box3f box = slabs.slab(k, n);
      for (int a = 0; a < 3; ++a) {
        ASSERT_LE(stretch.min[a], box.min[a]) << "trial " << trial << " slab " << k << " of " << n;
        ASSERT_GE(stretch.max[a], box.max[a]) << "trial " << trial << " slab " << k << " of " << n;
      }
    }
  }
}

TEST(EmptySpaceSlabs, CoverEveryPointOfTheEmptySpace) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> coordinate(-30.0, 30.0), unit(0.0, 1.0);
  for (int trial = 0; trial < 200; ++trial) {
    const TetrahedronCorners q{Vec3d{coordinate(rng), coordinate(rng), coordinate(rng)},
                               Vec3d{coordinate(rng), coordinate(rng), coordinate(rng)},
                               Vec3d{coordinate(rng), coordinate(rng), coordinate(rng)},
                               Vec3d{coordinate(rng), coordinate(rng), coordinate(rng)}};
    const EmptySpaceSlabs slabs(q);
    const int n = slab_count(q, 2.0);
    for (int sample = 0; sample < 200; ++sample) {
      // A point of the tetrahedron: barycentric weights, then the slab its distance along
      // the viewpoint's cone puts it in.
      double w1 = unit(rng), w2 = unit(rng), w3 = unit(rng);
      const double t = unit(rng), sum = w1 + w2 + w3;
      w1 /= sum, w2 /= sum, w3 /= sum;
      const Vec3d p = q[0] + ((q[1] - q[0]) * w1 + (q[2] - q[0]) * w2 + (q[3] - q[0]) * w3) * t;
      const int k = std::min(n - 1, static_cast<int>(t * n));
      const Box3f box = slabs.slab(k, n);
      const Vec3f pf(p);
      for (int a = 0; a < 3; ++a) {
        ASSERT_LE(box.min[a], pf[a]) << "trial " << trial;
        ASSERT_GE(box.max[a], pf[a]) << "trial " << trial;
      }
    }
  }
}

}  // namespace
}  // namespace citymesh::change_detail
