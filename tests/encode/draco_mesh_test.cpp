// SPDX-License-Identifier: MIT
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "citymesh/core/error.h"
#include "citymesh/encode/draco_mesh.h"
#include "grid_triangles.h"

namespace citymesh {
namespace {

struct Grid {
  std::vector<Vec3f> positions;
  std::vector<Triangle> triangles;
};

/// Columns first_column .. first_column + n of an infinite wavy grid.
Grid grid(int n, int first_column) {
  Grid g;
  for (int c = first_column; c <= first_column + n; ++c)
    for (int j = 0; j <= n; ++j)
      g.positions.push_back({0.37f * float(c), 0.41f * float(j), 0.05f * std::sin(float(c + j))});
  g.triangles = test::grid_triangles(n);
  return g;
}

/// Each triangle as its three corner positions, rotated to start at the smallest corner, sorted.
std::vector<std::array<Vec3f, 3>> corner_sets(const std::vector<Vec3f>& p, const std::vector<Triangle>& t) {
  auto less = [](const Vec3f& a, const Vec3f& b) { return std::tie(a.x, a.y, a.z) < std::tie(b.x, b.y, b.z); };
  std::vector<std::array<Vec3f, 3>> out;
  for (const Triangle& tri : t) {
    std::array<Vec3f, 3> c{p[tri[0]], p[tri[1]], p[tri[2]]};
    std::rotate(c.begin(), std::min_element(c.begin(), c.end(), less), c.end());
    out.push_back(c);
  }
  std::sort(out.begin(), out.end(), [&](const auto& a, const auto& b) {
    return std::lexicographical_compare(a.begin(), a.end(), b.begin(), b.end(), less);
  });
  return out;
}

TEST(Draco, RoundTripKeepsTrianglesWithinTheQuantizationStep) {
  const Grid g = grid(30, 0);
  DracoEncodeParams params;
  params.position_bits = 16;
  params.lattice = DracoLattice{{-1.f, -1.f, -1.f}, 16.f};
  const auto bytes = draco_encode(g.positions, g.triangles, params);
  EXPECT_LT(bytes.size(), g.positions.size() * 12 + g.triangles.size() * 12);  // it compresses
  const DecodedMesh d = draco_decode(bytes);
  ASSERT_EQ(d.triangles.size(), g.triangles.size());
  const float step = 16.f / float((1 << 16) - 1);
  // Snap the originals to the lattice ourselves, then the triangle sets must match.
  std::vector<Vec3f> snapped = g.positions;
  for (Vec3f& p : snapped) {
    for (int k = 0; k < 3; ++k) {
      const float q = std::round((p[k] - (-1.f)) / step);
      p[k] = -1.f + q * step;
    }
  }
  const auto expected = corner_sets(snapped, g.triangles), got = corner_sets(d.positions, d.triangles);
  ASSERT_EQ(expected.size(), got.size());
  for (std::size_t i = 0; i < got.size(); ++i) {
    for (int k = 0; k < 3; ++k) EXPECT_LE(norm(got[i][k] - expected[i][k]), step) << i;
  }
}

TEST(Draco, SharedLatticeDecodesEqualPositionsBitIdentically) {
  // Two neighbouring tiles share a border column of vertices: decoded, they must be identical.
  const Grid left = grid(10, 0), right = grid(10, 10);  // right's first column = left's last
  DracoEncodeParams params;
  params.lattice = DracoLattice{{-10.f, -10.f, -10.f}, 64.f};
  const DecodedMesh a = draco_decode(draco_encode(left.positions, left.triangles, params));
  const DecodedMesh b = draco_decode(draco_encode(right.positions, right.triangles, params));
  int shared = 0;
  for (const Vec3f& p : a.positions) {
    if (std::abs(p.x - 0.37f * 10.f) > 0.01f) continue;
    const bool found = std::any_of(b.positions.begin(), b.positions.end(), [&](const Vec3f& q) { return q == p; });
    EXPECT_TRUE(found) << p.x << " " << p.y;
    ++shared;
  }
  EXPECT_EQ(shared, 11);
}

TEST(Draco, CorruptBufferIsAnInputError) {
  const std::vector<std::uint8_t> junk{'D', 'R', 'A', 'C', 'O', 2, 2, 1, 0, 0, 9, 9};
  EXPECT_THROW(draco_decode(junk), InputError);
  EXPECT_THROW(draco_decode({}), InputError);
}

}  // namespace
}  // namespace citymesh
