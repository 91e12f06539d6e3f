// SPDX-License-Identifier: MIT
// Seams along creases cost crease_weight times more ([mosaic] crease_angle, crease_weight).
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>

#include "citymesh/mosaic/mosaic.h"
#include "grid_triangles.h"

namespace citymesh {
namespace {

using test::placed_grid;

/// Cell (i, j) of a placed grid holds triangles 2 (j columns + i) and the next one.
std::uint32_t first_triangle(int columns, int i, int j) { return static_cast<std::uint32_t>(2 * (j * columns + i)); }

/// An L: `ground` columns of 0.2 m on the ground from x = 0.6 to the foot of a wall at
/// x = 0.6 + 0.2 ground, then 10 columns of 0.1 m up the wall; 10 rows of 0.1 m along y.
Mesh corner(int ground) {
  const float foot = 0.6f + 0.2f * float(ground);
  return placed_grid(ground + 10, 10, [=](int i, int j) {
    const float y = 0.1f * float(j);
    if (i <= ground) return Vec3f{0.6f + 0.2f * float(i), y, 0.0f};
    return Vec3f{foot, y, 0.1f * float(i - ground)};
  });
}

Mesh flat(int columns) {
  return placed_grid(columns, 10, [](int i, int j) { return Vec3f{0.1f * float(i), 0.1f * float(j), 0.01f}; });
}

TEST(CreaseWeight, MultipliesTheSeamTermsAlongCreasesOnly) {
  const std::vector<Mesh> meshes{corner(2)};
  const std::vector<TimePoint> dates{TimePoint(std::chrono::days(1))};
  ChangeResult change;
  change.index.offsets = {0, static_cast<std::uint32_t>(meshes[0].triangle_count())};
  change.kept.assign(meshes[0].triangle_count(), 1);
  MosaicParams plain;
  plain.crease_weight = 1;
  MosaicParams creased;
  creased.crease_weight = 3;
  creased.crease_angle = 20;
  const MosaicEnergy a = build_mosaic_energy({meshes, dates, &change, 0.1, {}}, plain);
  const MosaicEnergy b = build_mosaic_energy({meshes, dates, &change, 0.1, {}}, creased);
  ASSERT_EQ(a.stats.seam_terms, b.stats.seam_terms);
  std::size_t creases = 0;
  for (std::size_t k = 0; k < a.stats.seam_terms; ++k) {
    const auto& p = a.energy.pairs[k];
    ASSERT_EQ(p.i, b.energy.pairs[k].i);
    ASSERT_EQ(p.j, b.energy.pairs[k].j);
    // The only crease is the wall's foot: one triangle of the pair on the ground (every
    // corner at z = 0), the other on the wall.
    const auto on_ground = [&](std::uint32_t v) {
      const auto c = meshes[0].corners(a.triangle_of[v]);
      return c[0].z == 0 && c[1].z == 0 && c[2].z == 0;
    };
    const bool crease = on_ground(p.i) != on_ground(p.j);
    creases += crease ? 1 : 0;
    EXPECT_GT(p.e01, 0);
    EXPECT_DOUBLE_EQ(b.energy.pairs[k].e01, p.e01 * (crease ? 3.0 : 1.0)) << "pair " << k;
    EXPECT_DOUBLE_EQ(b.energy.pairs[k].e10, p.e10 * (crease ? 3.0 : 1.0)) << "pair " << k;
  }
  EXPECT_EQ(creases, 10u) << "one crease edge per row";
}

TEST(CreaseWeight, MovesTheSeamOffTheCorner) {
  // Mesh 0 is an L (ground from x = 0.6 in 0.2 m columns, then a wall); mesh 1 is ground from
  // x = 0 to the wall's foot in finer 0.1 m columns, so that where the two overlap it offers
  // twice the triangles. Plain, mesh 1 takes the overlap and mesh 0 is cut along the wall's
  // foot. With seams along creases costing ten times more, no seam runs along the foot: it
  // moves onto a flat part, here one row up the wall (for this energy, dropping that row is
  // cheaper than the ground's extra triangles).
  const std::vector<Mesh> meshes{corner(2), flat(10)};
  const std::vector<TimePoint> dates{TimePoint(std::chrono::days(1)), TimePoint(std::chrono::days(40))};
  const auto n0 = static_cast<std::uint32_t>(meshes[0].triangle_count());
  const auto n1 = static_cast<std::uint32_t>(meshes[1].triangle_count());
  ChangeResult change;
  change.index.offsets = {0, n0, n0 + n1};
  change.kept.assign(n0 + n1, 1);
  std::vector<TrianglePair> pairs;
  for (int j = 0; j < 10; ++j) {
    for (int i = 0; i < 2; ++i) {
      for (int fine = 2 * i + 6; fine <= 2 * i + 7; ++fine) {
        for (std::uint32_t s = 0; s < 2; ++s) {
          for (std::uint32_t t = 0; t < 2; ++t) {
            pairs.emplace_back(first_triangle(12, i, j) + s, n0 + first_triangle(10, fine, j) + t);
          }
        }
      }
    }
  }
  change.consistent_pairs = std::move(pairs);
  // Along row j the foot is the edge between the first triangle of ground cell 1 and the
  // second of wall cell 2: a seam runs along it when exactly one of them is kept.
  const auto seams_along_foot = [&](const MosaicSelection& s) {
    int seams = 0;
    for (int j = 0; j < 10; ++j) seams += s.selected[first_triangle(12, 1, j)] != s.selected[first_triangle(12, 2, j) + 1];
    return seams;
  };
  const auto kept = [&](const MosaicSelection& s, std::uint32_t begin, std::uint32_t end) {
    int count = 0;
    for (std::uint32_t g = begin; g < end; ++g) count += s.selected[g];
    return count;
  };
  MosaicParams params;
  params.fill_holes = false;
  params.crease_weight = 1;
  const MosaicSelection plain = select_mosaic({meshes, dates, &change, 0.1, {}}, params);
  EXPECT_EQ(seams_along_foot(plain), 10);
  EXPECT_EQ(kept(plain, n0, n0 + n1), static_cast<int>(n1)) << "mesh 1 whole";
  params.crease_weight = 10;
  const MosaicSelection creased = select_mosaic({meshes, dates, &change, 0.1, {}}, params);
  EXPECT_EQ(seams_along_foot(creased), 0);
  EXPECT_EQ(kept(creased, n0, n0 + n1), static_cast<int>(n1)) << "mesh 1 whole";
  EXPECT_GT(kept(creased, 0, n0), 150) << "most of the wall";
}

}  // namespace
}  // namespace citymesh
