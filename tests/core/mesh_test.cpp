// SPDX-License-Identifier: MIT
#include <gtest/gtest.h>

#include "citymesh/core/error.h"
#include "citymesh/core/mesh.h"

namespace citymesh {
namespace {

Mesh one_triangle() {
  Mesh m;
  m.origin = {651000.0, 6860000.0, 40.0};
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  m.triangles = {{0, 1, 2}};
  m.triangle_ids = {{2, 0, 17}};
  return m;
}

TEST(Mesh, WorldPositionAddsTheOriginInDouble) {
  const Mesh m = one_triangle();
  EXPECT_EQ(m.world_position(1), (Vec3d{651001.0, 6860000.0, 40.0}));
  // A float cannot hold 6860000.3 to a millimetre; origin + local offset can.
  const Vec3d p{651000.123, 6860000.456, 41.789};
  const Vec3d back = m.origin + Vec3d(to_local(p, m.origin));
  EXPECT_NEAR(back.x, p.x, 1e-5);
  EXPECT_NEAR(back.y, p.y, 1e-5);
}

TEST(Mesh, InvariantsCatchSizeAndIndexErrors) {
  Mesh m = one_triangle();
  EXPECT_NO_THROW(m.check_invariants());
  m.times = {1.0};
  EXPECT_THROW(m.check_invariants(), ProcessingError);
  m = one_triangle();
  m.triangles[0][2] = 3;
  EXPECT_THROW(m.check_invariants(), ProcessingError);
  m = one_triangle();
  m.triangle_ids.clear();
  EXPECT_THROW(m.check_invariants(), ProcessingError);
}

TEST(TriangleId, OrdersByAcquisitionFaceThenFan) {
  EXPECT_LT((TriangleId{0, 5, 9}), (TriangleId{1, 0, 0}));
  EXPECT_LT((TriangleId{1, 5, 2}), (TriangleId{1, 0, 3}));
  EXPECT_LT((TriangleId{1, 0, 3}), (TriangleId{1, 1, 3}));
}

TEST(DoubledArea, IsTwiceTheTriangleArea) {
  EXPECT_DOUBLE_EQ(doubled_area({0, 0, 0}, {2, 0, 0}, {0, 3, 0}), 6.0);
  EXPECT_DOUBLE_EQ(doubled_area({0, 0, 0}, {1, 1, 1}, {2, 2, 2}), 0.0);
}

}  // namespace
}  // namespace citymesh
