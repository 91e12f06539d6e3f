// SPDX-License-Identifier: MIT
// map_to_local_frame against the exact conversion (Crs::to_ecef, EnuFrame::from_ecef).
#include "citymesh/geo/local_frame_map.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

namespace citymesh {
namespace {

constexpr VerticalDatum kOrthometric{VerticalDatum::Kind::orthometric, 44.6};

std::vector<Vec3d> random_points(const Vec3d& centre, const Vec3d& half, int count, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::vector<Vec3d> out;
  for (int i = 0; i < count; ++i) {
    out.push_back(centre + Vec3d{unit(rng) * half.x, unit(rng) * half.y, unit(rng) * half.z});
  }
  return out;
}

std::vector<Vec3f> exact_positions(std::span<const Vec3d> points, const Crs& crs, const EnuFrame& frame) {
  std::vector<Vec3f> out;
  for (const Vec3d& p : points) out.push_back(exact_local_position(crs, frame, p));
  return out;
}

/// How many coordinates differ from the exact ones; how many by more than a float's step at
/// the exact value (or than 1e-8 m, below which the exact conversion itself is not exact: its
/// ECEF doubles step by 1e-9 m), and the largest difference in metres.
struct Agreement {
  std::size_t differing = 0, beyond_a_step = 0;
  double largest = 0;
};

Agreement agreement(std::span<const Vec3f> fast, std::span<const Vec3f> exact) {
  Agreement out;
  for (std::size_t i = 0; i < fast.size(); ++i) {
    for (int axis = 0; axis < 3; ++axis) {
      const float e = std::abs(exact[i][axis]);
      const double step = std::max(double(std::nextafter(e, INFINITY) - e), 1e-8);
      const double difference = std::abs(double(fast[i][axis]) - double(exact[i][axis]));
      out.differing += difference > 0;
      out.beyond_a_step += difference > step;
      out.largest = std::max(out.largest, difference);
    }
  }
  return out;
}

struct Place {
  const char* crs;
  Vec3d centre;
};

TEST(LocalFrameMap, AgreesWithTheExactConversionWithinAFloatStepOverTwoKilometres) {
  for (const Place& place : {Place{"EPSG:2154", {651000, 6860700, 40}}, Place{"EPSG:32631", {448251, 5411943, 40}},
                             Place{"EPSG:32733", {300000, 6000000, 120}}, Place{"ENU:48.85,2.35,40", {100, 200, 10}}}) {
    const Crs crs = Crs::parse(place.crs, kOrthometric);
    const EnuFrame frame(crs.to_geodetic(place.centre));
    const std::vector<Vec3d> points = random_points(place.centre, {1000, 1000, 60}, 20000, 3);
    const Agreement a = agreement(map_to_local_frame(points, crs, frame), exact_positions(points, crs, frame));
    EXPECT_EQ(a.beyond_a_step, 0u) << place.crs << ": " << a.largest << " m";
    EXPECT_LE(a.differing, points.size() * 3 / 1000) << place.crs;  // a float rounds otherwise only rarely
  }
}

TEST(LocalFrameMap, AgreesWithinAFloatStepNearTheOriginWhereAStepIsNanometres) {
  // Around a corner of the lattice (multiples of 64 m): the points fall in eight cubes, and
  // within 5 cm of the frame's origin a float's step is 4 nm or less.
  const Crs crs = Crs::parse("EPSG:2154", kOrthometric);
  const Vec3d corner{651008, 6860672, 64};
  const EnuFrame frame(crs.to_geodetic(corner));
  const std::vector<Vec3d> points = random_points(corner, {0.05, 0.05, 0.05}, 20000, 5);
  const Agreement a = agreement(map_to_local_frame(points, crs, frame), exact_positions(points, crs, frame));
  EXPECT_EQ(a.beyond_a_step, 0u) << a.largest << " m";
}

TEST(LocalFrameMap, APositionMapsToTheSameBitsInAnyBatch) {
  const Crs crs = Crs::parse("EPSG:2154", kOrthometric);
  const EnuFrame frame(crs.to_geodetic({651000, 6860700, 40}));
  std::vector<Vec3d> points = random_points({651000, 6860700, 40}, {300, 300, 40}, 3000, 7);
  const std::vector<Vec3f> together = map_to_local_frame(points, crs, frame);
  for (std::size_t i = 0; i < points.size(); i += 97) {
    const std::vector<Vec3f> alone = map_to_local_frame(std::span(&points[i], 1), crs, frame);
    EXPECT_EQ(position_bits(alone[0]), position_bits(together[i]));
  }
  std::reverse(points.begin(), points.end());
  std::vector<Vec3f> reversed = map_to_local_frame(points, crs, frame);
  std::reverse(reversed.begin(), reversed.end());
  for (std::size_t i = 0; i < reversed.size(); ++i) EXPECT_EQ(position_bits(reversed[i]), position_bits(together[i]));
}

TEST(LocalFrameMap, ACubeWhoseInterpolantStraysMapsExactly) {
  // Cubes of 200 km: a quadratic strays by metres over them.
  const Crs crs = Crs::parse("EPSG:2154", kOrthometric);
  const EnuFrame frame(crs.to_geodetic({651000, 6860700, 40}));
  const std::vector<Vec3d> points = random_points({651000, 6860700, 40}, {50000, 50000, 60}, 2000, 11);
  const std::vector<Vec3f> exact = exact_positions(points, crs, frame);
  const Agreement checked = agreement(map_to_local_frame(points, crs, frame, {.cell = 2e5, .tolerance = 1e-6}), exact);
  EXPECT_EQ(checked.differing, 0u);
  // Without the check the same cubes would have been used, far from the exact positions.
  const std::vector<Vec3f> unchecked = map_to_local_frame(points, crs, frame, {.cell = 2e5, .tolerance = 1e9});
  double worst = 0;
  for (std::size_t i = 0; i < points.size(); ++i) worst = std::max(worst, double(norm(unchecked[i] - exact[i])));
  EXPECT_GT(worst, 0.01);
}

}  // namespace
}  // namespace citymesh
