// SPDX-License-Identifier: MIT
#include "citymesh/core/geometry.h"

#include <gtest/gtest.h>

#include <random>
#include <vector>

namespace citymesh {
namespace {

const TetrahedronCorners kUnit{{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};
/// A flattened "tetrahedron": the unit square in z = 0.
const TetrahedronCorners kFlatSquare{{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}}};

TriangleCorners shifted(TriangleCorners t, const Vec3d& by) {
  for (Vec3d& p : t) p = p + by;
  return t;
}

TEST(TriangleTetrahedron, FarApartIsDisjoint) {
  EXPECT_FALSE(triangle_intersects_tetrahedron({{{2, 2, 2}, {3, 2, 2}, {2, 3, 2}}}, kUnit));
}

TEST(TriangleTetrahedron, PiercingWithEveryCornerOutside) {
  EXPECT_TRUE(triangle_intersects_tetrahedron({{{-1, -1, 0.2}, {3, -1, 0.2}, {-1, 3, 0.2}}}, kUnit));
}

TEST(TriangleTetrahedron, SmallTriangleInside) {
  EXPECT_TRUE(triangle_intersects_tetrahedron({{{0.2, 0.2, 0.2}, {0.25, 0.2, 0.2}, {0.2, 0.25, 0.2}}}, kUnit));
}

TEST(TriangleTetrahedron, TouchingAtOneCornerCountsAndANearMissDoesNot) {
  const TriangleCorners touching{{{1, 0, 0}, {2, 0, 0}, {2, 1, 0}}};
  EXPECT_TRUE(triangle_intersects_tetrahedron(touching, kUnit));
  EXPECT_FALSE(triangle_intersects_tetrahedron(shifted(touching, {1e-6, 0, 0}), kUnit));
}

TEST(TriangleTetrahedron, TouchingAlongAnEdge) {
  const TriangleCorners touching{{{0, 0, 0}, {1, 0, 0}, {0.5, -1, 0}}};
  EXPECT_TRUE(triangle_intersects_tetrahedron(touching, kUnit));
  EXPECT_FALSE(triangle_intersects_tetrahedron(shifted(touching, {0, -1e-6, 0}), kUnit));
}

TEST(TriangleTetrahedron, TriangleThroughATetrahedronCorner) {
  // The plane z = 1 holds the apex (0, 0, 1) inside the triangle and nothing else of the tetrahedron.
  const TriangleCorners around_apex{{{-1, -1, 1}, {2, -1, 1}, {-1, 2, 1}}};
  EXPECT_TRUE(triangle_intersects_tetrahedron(around_apex, kUnit));
  EXPECT_FALSE(triangle_intersects_tetrahedron(shifted(around_apex, {0, 0, 1e-6}), kUnit));
}

TEST(TriangleTetrahedron, CoplanarWithAFace) {
  EXPECT_TRUE(triangle_intersects_tetrahedron({{{0.1, 0.1, 0}, {0.5, 0.1, 0}, {0.1, 0.5, 0}}}, kUnit));
  // In the face's plane, outside it: only an in-plane axis separates along the slanted edge.
  EXPECT_FALSE(triangle_intersects_tetrahedron({{{0.6, 0.6, 0}, {2, 0.6, 0}, {0.6, 2, 0}}}, kUnit));
  // Overlapping the face while sticking out of it.
  EXPECT_TRUE(triangle_intersects_tetrahedron({{{0.5, 0.5, 0}, {2, 0.5, 0}, {0.5, 2, 0}}}, kUnit));
}

TEST(TriangleTetrahedron, FlatTetrahedronIsHandledAsItsPolygon) {
  EXPECT_TRUE(triangle_intersects_tetrahedron({{{0.5, 0.5, -1}, {0.6, 0.5, 1}, {0.5, 0.6, 1}}}, kFlatSquare));
  // Coplanar and beyond the square's corner (1, 1): separated only within the plane.
  EXPECT_FALSE(triangle_intersects_tetrahedron({{{1.2, 1.2, 0}, {2, 1.2, 0}, {1.2, 2, 0}}}, kFlatSquare));
  EXPECT_TRUE(triangle_intersects_tetrahedron({{{1, 1, 0}, {2, 1, 0}, {1, 2, 0}}}, kFlatSquare));
  // Coplanar, beyond the diagonal the square's hull would not have if it were only a triangle.
  EXPECT_TRUE(triangle_intersects_tetrahedron({{{0.9, 0.9, 0}, {2, 0.9, 0}, {0.9, 2, 0}}}, kFlatSquare));
  // Above the square's plane: disjoint.
  EXPECT_FALSE(triangle_intersects_tetrahedron({{{0.5, 0.5, 0.1}, {0.6, 0.5, 0.1}, {0.5, 0.6, 0.2}}}, kFlatSquare));
}

TEST(TriangleTetrahedron, SegmentLikeTriangle) {
  const TriangleCorners segment{{{0.2, 0.2, -1}, {0.2, 0.2, 2}, {0.2, 0.2, 0.5}}};
  EXPECT_TRUE(triangle_intersects_tetrahedron(segment, kUnit));
  EXPECT_FALSE(triangle_intersects_tetrahedron(shifted(segment, {1, 1, 0}), kUnit));
  // A segment lying in the flat square's plane, crossing it, then beside it.
  const TriangleCorners in_plane{{{-1, 0.5, 0}, {2, 0.5, 0}, {0.5, 0.5, 0}}};
  EXPECT_TRUE(triangle_intersects_tetrahedron(in_plane, kFlatSquare));
  EXPECT_FALSE(triangle_intersects_tetrahedron(shifted(in_plane, {0, 0.6, 0}), kFlatSquare));
}

// ---- random cases against an independent algorithm: clip the triangle by the tetrahedron's
// half-spaces (Sutherland-Hodgman) and see whether anything is left.

/// Clipped polygon non-empty, with every face plane moved outwards by `grow` metres.
bool clip_reference(const TriangleCorners& t, const TetrahedronCorners& q, double grow) {
  std::vector<Vec3d> poly(t.begin(), t.end());
  const Vec3d centre = (q[0] + q[1] + q[2] + q[3]) * 0.25;
  const int faces[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
  for (const auto& f : faces) {
    Vec3d n = cross(q[f[1]] - q[f[0]], q[f[2]] - q[f[0]]);
    n = n / norm(n);
    if (dot(centre - q[f[0]], n) < 0) n = n * -1.0;  // inward
    const auto inside = [&](const Vec3d& p) { return dot(p - q[f[0]], n) + grow; };
    std::vector<Vec3d> out;
    for (std::size_t i = 0; i < poly.size(); ++i) {
      const Vec3d& a = poly[i];
      const Vec3d& b = poly[(i + 1) % poly.size()];
      const double da = inside(a), db = inside(b);
      if (da >= 0) out.push_back(a);
      if ((da >= 0) != (db >= 0)) out.push_back(a + (b - a) * (da / (da - db)));
    }
    poly = std::move(out);
    if (poly.empty()) return false;
  }
  return true;
}

TEST(TriangleTetrahedron, AgreesWithClippingOnRandomShapes) {
  std::mt19937_64 rng(17);
  std::uniform_real_distribution<double> coord(-1.0, 1.0);
  const auto point = [&] { return Vec3d{coord(rng), coord(rng), coord(rng)}; };
  int compared = 0, intersecting = 0;
  for (int i = 0; i < 20000; ++i) {
    const TetrahedronCorners q{point(), point(), point(), point()};
    const Vec3d c = point() * 0.8;
    const TriangleCorners t{c + point() * 0.5, c + point() * 0.5, c + point() * 0.5};
    const bool grown = clip_reference(t, q, 1e-9), shrunk = clip_reference(t, q, -1e-9);
    if (grown != shrunk) continue;  // within rounding of touching: no reference answer
    ++compared;
    intersecting += grown ? 1 : 0;
    ASSERT_EQ(triangle_intersects_tetrahedron(t, q), grown) << "case " << i;
  }
  EXPECT_GT(compared, 19000);
  EXPECT_GT(intersecting, 2000);
  EXPECT_LT(intersecting, compared - 2000);
}

// ---- point to triangle distance

TEST(PointTriangleDistance, RegionsOfATriangle) {
  const TriangleCorners t{{{0, 0, 0}, {2, 0, 0}, {0, 2, 0}}};
  EXPECT_DOUBLE_EQ(point_triangle_distance_sq({0.5, 0.5, 3}, t), 9.0);   // above the face
  EXPECT_DOUBLE_EQ(point_triangle_distance_sq({1, -1, 0}, t), 1.0);      // beside an edge
  EXPECT_DOUBLE_EQ(point_triangle_distance_sq({-1, -1, 0}, t), 2.0);     // beyond a corner
  EXPECT_DOUBLE_EQ(point_triangle_distance_sq({2, 2, 0}, t), 2.0);       // beside the hypotenuse
  EXPECT_DOUBLE_EQ(point_triangle_distance_sq({0, 0, 0}, t), 0.0);
}

TEST(PointTriangleDistance, DegenerateTriangleIsASegment) {
  const TriangleCorners segment{{{0, 0, 0}, {1, 0, 0}, {2, 0, 0}}};
  EXPECT_DOUBLE_EQ(point_triangle_distance_sq({1.5, 1, 0}, segment), 1.0);
  EXPECT_DOUBLE_EQ(point_triangle_distance_sq({3, 0, 0}, segment), 1.0);
}

TEST(PointTriangleDistance, AgreesWithDenseSampling) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> coord(-1.0, 1.0);
  const auto point = [&] { return Vec3d{coord(rng), coord(rng), coord(rng)}; };
  for (int i = 0; i < 300; ++i) {
    const TriangleCorners t{point(), point(), point()};
    const Vec3d p = point() * 1.5;
    double sampled = 1e300;
    const int n = 300;
    for (int a = 0; a <= n; ++a) {
      for (int b = 0; a + b <= n; ++b) {
        const double u = double(a) / n, v = double(b) / n;
        const Vec3d q = t[0] + (t[1] - t[0]) * u + (t[2] - t[0]) * v;
        sampled = std::min(sampled, dot(p - q, p - q));
      }
    }
    const double exact = std::sqrt(point_triangle_distance_sq(p, t));
    ASSERT_LE(exact, std::sqrt(sampled) + 1e-12) << "case " << i;
    ASSERT_GE(exact, std::sqrt(sampled) - 4.0 / n) << "case " << i;  // the samples are 2/n * edge apart
  }
}

}  // namespace
}  // namespace citymesh
