// SPDX-License-Identifier: MIT
#include "citymesh/core/vec.h"

#include <gtest/gtest.h>

namespace citymesh {
namespace {

Box3d unit_box() {
  Box3d b;
  b.extend(Vec3d{0, 0, 0});
  b.extend(Vec3d{1, 2, 3});
  return b;
}

TEST(Box3d, ContainsIsClosedOnEveryFace) {
  const Box3d b = unit_box();
  EXPECT_TRUE(b.contains({0, 0, 0}));
  EXPECT_TRUE(b.contains({1, 2, 3}));
  EXPECT_TRUE(b.contains({0.5, 1, 1.5}));
  EXPECT_FALSE(b.contains({1.0000001, 1, 1}));
  EXPECT_FALSE(b.contains({0.5, -1e-9, 1}));
  EXPECT_FALSE(b.contains({0.5, 1, 3.5}));
}

TEST(Box3d, GrownMovesEveryFaceOutByThePad) {
  const Box3d g = unit_box().grown(0.25);
  EXPECT_EQ(g.min.x, -0.25);
  EXPECT_EQ(g.min.y, -0.25);
  EXPECT_EQ(g.min.z, -0.25);
  EXPECT_EQ(g.max.x, 1.25);
  EXPECT_EQ(g.max.y, 2.25);
  EXPECT_EQ(g.max.z, 3.25);
  EXPECT_TRUE(g.contains({1.2, 2.2, -0.2}));
}

TEST(Box3d, AnEmptyBoxStaysEmptyWhenGrown) {
  EXPECT_TRUE(Box3d{}.grown(1.0).empty());
  EXPECT_FALSE(Box3d{}.grown(1.0).contains({0, 0, 0}));
}

}  // namespace
}  // namespace citymesh
