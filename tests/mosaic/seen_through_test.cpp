// SPDX-License-Identifier: MIT
#include <gtest/gtest.h>

#include <array>
#include <chrono>
#include <cmath>
#include <random>

#include "citymesh/mosaic/mosaic.h"
#include "seen_through.h"

namespace citymesh {
namespace {

using mosaic_detail::seen_through;
using mosaic_detail::SeenThroughParams;

/// One triangle per entry, with its own three vertices; every vertex measured from `sensor`.
Mesh triangles_seen_from(const std::vector<std::array<Vec3f, 3>>& corners, const std::vector<Vec3f>& sensors) {
  Mesh m;
  for (std::size_t t = 0; t < corners.size(); ++t) {
    const auto base = static_cast<std::uint32_t>(m.positions.size());
    for (const Vec3f& c : corners[t]) {
      m.positions.push_back(c);
      m.sensor_positions.push_back(sensors[t]);
    }
    m.triangles.push_back({base, base + 1, base + 2});
  }
  m.triangle_ids.resize(m.triangles.size());
  return m;
}

/// A small triangle around p, facing up.
std::array<Vec3f, 3> around(Vec3f p) {
  return {p + Vec3f{-0.02f, -0.02f, 0}, p + Vec3f{0.03f, -0.01f, 0}, p + Vec3f{-0.01f, 0.03f, 0}};
}

TEST(SeenThrough, CentroidsInFrontOfAnotherPassSurfaceWithinItsEmptySpace) {
  // Pass 1: a 4 m x 4 m floor at z = 0 seen from 10 m above its middle. Pass 0's small
  // triangles stand at various places; only those over the floor, between the margin and the
  // depth above it, were seen through.
  const std::vector<std::array<Vec3f, 3>> floor{{Vec3f{-2, -2, 0}, Vec3f{2, -2, 0}, Vec3f{2, 2, 0}},
                                                {Vec3f{-2, -2, 0}, Vec3f{2, 2, 0}, Vec3f{-2, 2, 0}}};
  const Vec3f above{0, 0, 10};
  struct Case {
    Vec3f at;
    bool seen;
  };
  const std::vector<Case> cases{{{0.5f, 0.5f, 0.3f}, true},    // in front, within the depth
                                {{-1.0f, 1.2f, 0.9f}, true},   // still within 1 m
                                {{0.5f, 0.5f, 0.05f}, false},  // on the surface (within the margin)
                                {{0.5f, 0.5f, -0.3f}, false},  // behind it
                                {{0.5f, 0.5f, 1.5f}, false},   // beyond the depth searched
                                {{2.6f, 0.0f, 0.3f}, false}};  // beside it: outside the tetrahedron
  std::vector<std::array<Vec3f, 3>> small;
  for (const Case& c : cases) small.push_back(around(c.at));
  const std::vector<Mesh> meshes{triangles_seen_from(small, std::vector<Vec3f>(small.size(), above)),
                                 triangles_seen_from(floor, {above, above})};
  std::vector<std::uint32_t> ids(cases.size());
  for (std::uint32_t i = 0; i < ids.size(); ++i) ids[i] = i;
  GlobalTriangles index;
  index.offsets = {0, cases.size(), cases.size() + 2};
  const std::vector<std::uint8_t> seen = seen_through(meshes, index, ids, {.margin = 0.1, .depth = 1.0});
  for (std::size_t i = 0; i < cases.size(); ++i) EXPECT_EQ(seen[i] != 0, cases[i].seen) << "case " << i;
  // Its own mesh never counts, nor a pass without sensor positions.
  const auto floor_id = static_cast<std::uint32_t>(cases.size());
  EXPECT_EQ(seen_through(meshes, index, std::vector<std::uint32_t>{floor_id, floor_id + 1}, {}),
            (std::vector<std::uint8_t>{0, 0}));
  Mesh blind = meshes[1];
  blind.sensor_positions.clear();
  const std::vector<Mesh> without{meshes[0], blind};
  EXPECT_EQ(seen_through(without, index, ids, {})[0], 0);
}

/// Brute force: p inside the tetrahedron (v, q) when its barycentric coordinates are all
/// positive, and between margin and depth from q's plane, and within depth of q's box.
bool brute_force_seen(const Vec3d& p, const Vec3d& v, const std::array<Vec3d, 3>& q, const SeenThroughParams& params) {
  const auto det = [](const Vec3d& a, const Vec3d& b, const Vec3d& c) { return dot(a, cross(b, c)); };
  const double whole = det(q[0] - v, q[1] - v, q[2] - v);
  if (whole == 0) return false;
  const double b0 = det(p - v, q[1] - v, q[2] - v) / whole, b1 = det(q[0] - v, p - v, q[2] - v) / whole,
               b2 = det(q[0] - v, q[1] - v, p - v) / whole;
  if (b0 < 0 || b1 < 0 || b2 < 0 || b0 + b1 + b2 > 1) return false;
  const Vec3d n = cross(q[1] - q[0], q[2] - q[0]) / norm(cross(q[1] - q[0], q[2] - q[0]));
  const double h = std::abs(dot(p - q[0], n));
  if (h <= params.margin || h > params.depth) return false;
  for (int axis = 0; axis < 3; ++axis) {
    const auto coord = [axis](const Vec3d& x) { return axis == 0 ? x.x : axis == 1 ? x.y : x.z; };
    const double lo = std::min({coord(q[0]), coord(q[1]), coord(q[2])}) - params.depth;
    const double hi = std::max({coord(q[0]), coord(q[1]), coord(q[2])}) + params.depth;
    if (coord(p) < lo || coord(p) > hi) return false;
  }
  return true;
}

TEST(SeenThrough, AgreesWithBarycentricCoordinatesOnRandomScenes) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-1.5f, 1.5f), corner(-0.4f, 0.4f), height(2.0f, 8.0f);
  const SeenThroughParams params{.margin = 0.1, .depth = 0.8};
  std::size_t seen_count = 0;
  for (int scene = 0; scene < 20; ++scene) {
    std::vector<Mesh> meshes;
    for (int pass = 0; pass < 3; ++pass) {
      std::vector<std::array<Vec3f, 3>> corners;
      std::vector<Vec3f> sensors;
      for (int t = 0; t < 60; ++t) {
        const Vec3f c{u(rng), u(rng), u(rng) * 0.3f};
        corners.push_back({c + Vec3f{corner(rng), corner(rng), corner(rng) * 0.2f},
                           c + Vec3f{corner(rng), corner(rng), corner(rng) * 0.2f},
                           c + Vec3f{corner(rng), corner(rng), corner(rng) * 0.2f}});
        sensors.push_back({u(rng) * 3, u(rng) * 3, height(rng)});
      }
      meshes.push_back(triangles_seen_from(corners, sensors));
    }
    GlobalTriangles index;
    index.offsets = {0, 60, 120, 180};
    std::vector<std::uint32_t> ids(meshes[0].triangle_count());
    for (std::uint32_t i = 0; i < ids.size(); ++i) ids[i] = i;
    const std::vector<std::uint8_t> seen = seen_through(meshes, index, ids, params);
    for (std::uint32_t i = 0; i < ids.size(); ++i) {
      const auto [a, b, c] = meshes[0].corners(i);
      const Vec3d p = (a + b + c) / 3.0;
      bool expected = false;
      for (std::size_t m = 1; m < meshes.size() && !expected; ++m) {
        for (std::size_t t = 0; t < meshes[m].triangle_count() && !expected; ++t) {
          expected = brute_force_seen(p, meshes[m].viewpoint(t), meshes[m].corners(t), params);
        }
      }
      EXPECT_EQ(seen[i] != 0, expected) << "scene " << scene << ", triangle " << i;
      seen_count += expected ? 1 : 0;
    }
  }
  EXPECT_GT(seen_count, 50u) << "the scenes must exercise the positive case";
}

TEST(FillHoles, LeavesOutWhatAnotherPassSawThrough) {
  // The selection (pass 1) is a floor seen from above; pass 0 (kept, not selected) has a
  // floor of its own 0.3 m higher - more than the threshold away, so the fill would take it -
  // which pass 1 saw through. With sensor positions it stays out; without, the fill takes it.
  const std::vector<std::array<Vec3f, 3>> floor{{Vec3f{-2, -2, 0}, Vec3f{2, -2, 0}, Vec3f{2, 2, 0}},
                                                {Vec3f{-2, -2, 0}, Vec3f{2, 2, 0}, Vec3f{-2, 2, 0}}};
  std::vector<std::array<Vec3f, 3>> raised;
  for (const Vec3f& p : {Vec3f{0.5f, 0.5f, 0.3f}, Vec3f{-0.5f, 0.2f, 0.3f}, Vec3f{5.0f, 5.0f, 0.3f}}) {
    raised.push_back(around(p));
  }
  const Vec3f above{0, 0, 10};
  std::vector<Mesh> meshes{triangles_seen_from(raised, std::vector<Vec3f>(3, above)),
                           triangles_seen_from(floor, {above, above})};
  const std::vector<TimePoint> dates{TimePoint(std::chrono::days(1)), TimePoint(std::chrono::days(40))};
  ChangeResult change;
  change.index.offsets = {0, 3, 5};
  change.kept.assign(5, 1);
  std::vector<std::uint8_t> selected{0, 0, 0, 1, 1};
  const HoleFillCounts counts = fill_holes({meshes, dates, &change, 0.1, {}}, selected);
  EXPECT_EQ(counts.added, 1u);
  EXPECT_EQ(counts.seen_through, 2u);
  EXPECT_EQ(selected, (std::vector<std::uint8_t>{0, 0, 1, 1, 1})) << "only the one beside the floor";

  for (Mesh& m : meshes) m.sensor_positions.clear();
  std::vector<std::uint8_t> blind{0, 0, 0, 1, 1};
  EXPECT_EQ(fill_holes({meshes, dates, &change, 0.1, {}}, blind).added, 3u);
}

}  // namespace
}  // namespace citymesh
