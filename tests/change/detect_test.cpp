// SPDX-License-Identifier: MIT
#include "citymesh/change/detect.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <set>

#include "citymesh/core/error.h"
#include "citymesh/core/geometry.h"
#include "citymesh/core/parallel.h"
#include "citymesh/scan/sensor_grid.h"
#include "citymesh/sim/scanner.h"
#include "citymesh/sim/scene.h"
#include "frames.h"

namespace citymesh {
namespace {

using namespace std::chrono_literals;

const TimePoint kDay0 = parse_iso8601("2026-01-05T10:00:00Z", "test");
TimePoint day(int d) { return kDay0 + std::chrono::days(d); }

/// A grid of square cells (two triangles each) in the plane z = height over [x0, x1] x [y0, y1],
/// seen from a sensor at `sensor`, with optional per-vertex jitter of the height.
void add_patch(Mesh& m, double x0, double x1, double y0, double y1, double height, double cell, const Vec3f& sensor,
               std::mt19937* jitter = nullptr) {
  const auto nx = static_cast<std::uint32_t>(std::lround((x1 - x0) / cell));
  const auto ny = static_cast<std::uint32_t>(std::lround((y1 - y0) / cell));
  const auto base = static_cast<std::uint32_t>(m.positions.size());
  std::normal_distribution<float> noise(0.0f, 0.004f);
  for (std::uint32_t j = 0; j <= ny; ++j) {
    for (std::uint32_t i = 0; i <= nx; ++i) {
      const float z = static_cast<float>(height) + (jitter != nullptr ? noise(*jitter) : 0.0f);
      m.positions.push_back({static_cast<float>(x0 + i * cell), static_cast<float>(y0 + j * cell), z});
      m.sensor_positions.push_back(sensor);
    }
  }
  for (std::uint32_t j = 0; j < ny; ++j) {
    for (std::uint32_t i = 0; i < nx; ++i) {
      const std::uint32_t a = base + j * (nx + 1) + i, b = a + 1, c = a + nx + 1, d = c + 1;
      m.triangles.push_back({a, b, d});
      m.triangles.push_back({a, d, c});
    }
  }
}

void finish(Mesh& m, std::uint32_t acquisition) {
  m.triangle_ids.clear();
  for (std::size_t t = 0; t < m.triangle_count(); ++t) m.triangle_ids.push_back({acquisition, 0, t});
}

/// A wall (plane x = x_wall, facing -x) from y0 to y1, z0 to z1.
void add_wall(Mesh& m, double x_wall, double y0, double y1, double z0, double z1, double cell, const Vec3f& sensor) {
  const std::size_t first = m.positions.size();
  add_patch(m, y0, y1, z0, z1, x_wall, cell, sensor);
  for (std::size_t v = first; v < m.positions.size(); ++v) {
    const Vec3f p = m.positions[v];
    m.positions[v] = {p.z, p.x, p.y};  // (y, z, x) -> (x, y, z)
  }
}

ChangeResult detect(const std::vector<Mesh>& meshes, const std::vector<TimePoint>& dates, ChangeParams params = {}) {
  return detect_changes({meshes, dates}, params);
}

// ---- consistency against brute force --------------------------------------------------

bool projects_inside(const Vec3d& c, const TriangleCorners& q, double threshold) {
  Vec3d n = cross(q[1] - q[0], q[2] - q[0]);
  n = n / norm(n);
  const double h = dot(c - q[0], n);
  if (std::abs(h) > threshold) return false;
  const Vec3d p = c - n * h;
  // Barycentric coordinates of p.
  const Vec3d v0 = q[1] - q[0], v1 = q[2] - q[0], v2 = p - q[0];
  const double d00 = dot(v0, v0), d01 = dot(v0, v1), d11 = dot(v1, v1), d20 = dot(v2, v0), d21 = dot(v2, v1);
  const double den = d00 * d11 - d01 * d01;
  const double b = (d11 * d20 - d01 * d21) / den, g = (d00 * d21 - d01 * d20) / den;
  return b >= -1e-9 && g >= -1e-9 && b + g <= 1 + 1e-9;
}

TEST(Consistency, PairsEqualBruteForceOnNoisyOverlappingPatches) {
  std::mt19937 rng(11);
  std::vector<Mesh> meshes(3);
  // Three passes over the same ground at different resolutions and offsets, one with a
  // tilted patch (normals too far apart) and one with a patch 30 cm up (too far).
  add_patch(meshes[0], 0, 3, 0, 2, 0.0, 0.1, {1.5f, -3, 2.5f}, &rng);
  add_patch(meshes[1], 0.05, 3.05, 0.02, 2.02, 0.0, 0.15, {1.5f, -3, 2.5f}, &rng);
  add_patch(meshes[1], 0, 1, 3, 4, 0.3, 0.1, {0.5f, 1, 2.5f});
  add_patch(meshes[2], 0.5, 2.5, 0.5, 1.5, 0.05, 0.25, {1.5f, -3, 2.5f}, &rng);
  add_patch(meshes[0], 0, 1, 3, 4, 0.0, 0.1, {0.5f, 1, 2.5f});
  for (std::uint32_t a = 0; a < 3; ++a) finish(meshes[a], a);
  const ChangeResult r = detect(meshes, {day(0), day(10), day(40)});

  std::vector<TrianglePair> expected;
  std::vector<std::pair<std::uint32_t, std::size_t>> all;  // (acquisition, triangle)
  for (std::uint32_t a = 0; a < 3; ++a) {
    for (std::size_t t = 0; t < meshes[a].triangle_count(); ++t) all.emplace_back(a, t);
  }
  const auto corners = [&](std::uint32_t a, std::size_t t) {
    const Mesh& m = meshes[a];
    return TriangleCorners{Vec3d(m.positions[m.triangles[t][0]]), Vec3d(m.positions[m.triangles[t][1]]),
                           Vec3d(m.positions[m.triangles[t][2]])};
  };
  const auto up_normal = [&](const TriangleCorners& q) {
    Vec3d n = cross(q[1] - q[0], q[2] - q[0]);
    n = n / norm(n);
    return n.z < 0 ? n * -1.0 : n;  // every sensor is above: normals face up
  };
  for (std::size_t i = 0; i < all.size(); ++i) {
    for (std::size_t j = i + 1; j < all.size(); ++j) {
      if (all[i].first == all[j].first) continue;
      const TriangleCorners p = corners(all[i].first, all[i].second), q = corners(all[j].first, all[j].second);
      if (dot(up_normal(p), up_normal(q)) < std::cos(45.0 * M_PI / 180)) continue;
      const Vec3d cp = (p[0] + p[1] + p[2]) / 3.0, cq = (q[0] + q[1] + q[2]) / 3.0;
      if (projects_inside(cp, q, 0.1) || projects_inside(cq, p, 0.1)) {
        expected.emplace_back(static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(j));
      }
    }
  }
  ASSERT_GT(expected.size(), 500u);
  EXPECT_EQ(r.consistent_pairs.unpacked(), expected);
}

/// Two turns of a spinning scanner over the same ground in one acquisition: every pair of
/// overlapping triangles of that pass sharing no corner is a layer pair, found as brute force
/// finds it; neighbours on one turn are not; the layers touch no label (the same states as the
/// two turns given as two passes would not be: there they are consistent).
TEST(Consistency, LayerPairsOfOnePassEqualBruteForceAndLeaveTheLabelsAlone) {
  std::mt19937 rng(5);
  std::vector<Mesh> meshes(2);
  add_patch(meshes[0], 0, 2, 0, 2, 0.0, 0.1, {1, -3, 2.5f}, &rng);               // turn 1
  add_patch(meshes[0], 0.53, 2.53, 0.31, 2.31, 0.02, 0.12, {1, 4, 2.5f}, &rng);  // turn 2, overlapping
  add_patch(meshes[1], 5, 6, 0, 1, 0.0, 0.1, {5.5f, -3, 2.5f});                  // elsewhere
  for (std::uint32_t a = 0; a < 2; ++a) finish(meshes[a], a);
  const ChangeResult r = detect(meshes, {day(0), day(40)});

  const Mesh& m = meshes[0];
  const auto corners = [&](std::size_t t) {
    return TriangleCorners{Vec3d(m.positions[m.triangles[t][0]]), Vec3d(m.positions[m.triangles[t][1]]),
                           Vec3d(m.positions[m.triangles[t][2]])};
  };
  const auto share_a_vertex = [&](std::size_t a, std::size_t b) {
    for (const std::uint32_t v : m.triangles[a]) {
      if (std::find(m.triangles[b].begin(), m.triangles[b].end(), v) != m.triangles[b].end()) return true;
    }
    return false;
  };
  std::vector<TrianglePair> expected;
  std::size_t across_turns = 0;
  const std::size_t first_of_turn_2 = 2 * 20 * 20;
  for (std::size_t i = 0; i < m.triangle_count(); ++i) {
    for (std::size_t j = i + 1; j < m.triangle_count(); ++j) {
      if (share_a_vertex(i, j)) continue;
      const TriangleCorners p = corners(i), q = corners(j);
      const Vec3d cp = (p[0] + p[1] + p[2]) / 3.0, cq = (q[0] + q[1] + q[2]) / 3.0;
      if (projects_inside(cp, q, 0.1) || projects_inside(cq, p, 0.1)) {
        expected.emplace_back(static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(j));
        across_turns += (i < first_of_turn_2) != (j < first_of_turn_2) ? 1 : 0;
      }
    }
  }
  ASSERT_GT(expected.size(), 300u);
  EXPECT_EQ(across_turns, expected.size());  // no pair within one turn
  EXPECT_EQ(r.layer_pairs.unpacked(), expected);
  EXPECT_TRUE(r.consistent_pairs.empty());
  for (std::size_t g = 0; g < r.state.size(); ++g) {
    EXPECT_EQ(r.state[g], TriangleState::single) << g;
    EXPECT_EQ(r.first_seen[g], r.last_seen[g]) << g;
  }
}

// ---- conflicts ---------------------------------------------------------------------------

/// Ground seen from x = -5 in both passes; the older pass also saw a wall at x = 2 which the
/// newer pass sees through (the ground behind it is seen).
std::vector<Mesh> wall_then_gone() {
  std::vector<Mesh> m(2);
  const Vec3f sensor{-5, 1, 2.5f};
  add_patch(m[0], -4, 1.8, 0, 2, 0.0, 0.2, sensor);  // 29 x 10 cells
  add_wall(m[0], 2.0, 0, 2, 0.2, 1.8, 0.2, sensor);
  add_patch(m[1], -4, 30, -8, 10, 0.0, 0.2, sensor);  // far and wide enough to see through all the wall
  finish(m[0], 0);
  finish(m[1], 1);
  return m;
}

TEST(Conflicts, ASurfaceSeenThroughLaterConflictsAndTheGroundStays) {
  const std::vector<Mesh> m = wall_then_gone();
  const ChangeResult r = detect(m, {day(0), day(40)});
  const std::size_t ground0 = 2 * 29 * 10;  // triangles of the first patch
  for (std::size_t t = 0; t < m[0].triangle_count(); ++t) {
    const bool wall = t >= ground0;
    EXPECT_EQ(r.state[t], wall ? TriangleState::conflicting : TriangleState::consistent) << t;
    EXPECT_EQ(r.kept[t], wall ? 0 : 1) << t;
  }
  // Newer ground behind the old wall proves it gone: some of it refutes.
  EXPECT_GT(std::count(r.refutes.begin() + r.index.offsets[1], r.refutes.end(), 1), 10);
}

TEST(Conflicts, ANewSurfaceInOlderEmptySpaceIsNotAConflict) {
  std::vector<Mesh> m = wall_then_gone();
  std::swap(m[0], m[1]);  // the wall is now the newer pass
  finish(m[0], 0);
  finish(m[1], 1);
  const ChangeResult r = detect(m, {day(0), day(40)});
  EXPECT_EQ(std::count(r.state.begin(), r.state.end(), TriangleState::conflicting), 0);
}

TEST(Conflicts, NoiseWithinTheMarginIsNotAConflict) {
  std::mt19937 rng(2);
  std::vector<Mesh> m(2);
  // Same ground, the older one 6 cm higher and coarser in places: consistent or within the margin.
  add_patch(m[0], 0, 4, 0, 2, 0.06, 0.3, {2, -4, 2.5f}, &rng);
  add_patch(m[1], 0, 4, 0, 2, 0.0, 0.1, {2, -4, 2.5f}, &rng);
  finish(m[0], 0);
  finish(m[1], 1);
  ChangeParams p;
  p.normal_angle = 0.001;  // nothing is consistent: only the margin protects the older ground
  const ChangeResult r = detect(m, {day(0), day(40)}, p);
  EXPECT_EQ(std::count(r.state.begin(), r.state.end(), TriangleState::conflicting), 0);
}

/// A newer facet from a sample on a cornice's underside (20 m from the sensor) to the next
/// sample of the scan line on the wall above (22 m), as a scan-line mesher strings it across
/// the lip; and two small older surfaces inside its tetrahedron, at `near` and `far` of the way
/// from the sensor to the facet's centroid.
std::vector<Mesh> facet_across_a_lip(float near, float far) {
  std::vector<Mesh> m(2);
  const Vec3f sensor{0, 0, 0};
  const Vec3f a{-0.5f, 20, 0}, b{0.5f, 20, 0}, c{0, 22, 2};
  const Vec3f centroid = (a + b + c) / 3.0f;
  for (const float s : {near, far}) {
    const Vec3f p = centroid * s;
    const auto base = static_cast<std::uint32_t>(m[0].positions.size());
    for (const Vec3f& d : {Vec3f{-0.02f, 0, 0}, Vec3f{0.02f, 0, 0}, Vec3f{0, 0, 0.03f}}) {
      m[0].positions.push_back(p + d);
      m[0].sensor_positions.push_back(sensor);
    }
    m[0].triangles.push_back({base, base + 1, base + 2});
  }
  m[1].positions = {a, b, c};
  m[1].sensor_positions = {sensor, sensor, sensor};
  m[1].triangles.push_back({0, 1, 2});
  finish(m[0], 0);
  finish(m[1], 1);
  return m;
}

TEST(Conflicts, NearestSampleReachClaimsNoEmptySpaceBeyondTheNearestCorner) {
  // The far surface is 42 cm in front of the facet's plane but beyond its nearest corner's
  // range less the margin (20.06 m > 19.91 m); the near one is 12 m from the sensor.
  const std::vector<Mesh> m = facet_across_a_lip(0.6f, 0.97f);
  const ChangeResult whole = detect(m, {day(0), day(40)});
  EXPECT_EQ(whole.state[0], TriangleState::conflicting);
  EXPECT_EQ(whole.state[1], TriangleState::conflicting);
  ChangeParams p;
  p.empty_space = EmptySpaceReach::nearest_sample;
  const ChangeResult nearest = detect(m, {day(0), day(40)}, p);
  EXPECT_EQ(nearest.state[0], TriangleState::conflicting);
  EXPECT_EQ(nearest.state[1], TriangleState::single);
  EXPECT_EQ(nearest.refutes[2], 1);
}

/// Older small facets scattered at random heights over a ground, and a newer ground seen from
/// far off at a slant: its empty spaces are up to ~60 m long, so the conflict search cuts each
/// into many slabs. Some facets stand inside the newer empty spaces, some beside or under them.
std::vector<Mesh> facets_under_slanted_rays(std::mt19937& rng, double newer_cell) {
  std::vector<Mesh> m(3);
  std::uniform_real_distribution<float> x(-4, 20), y(-6, 6), z(0.05f, 6), tilt(-0.3f, 0.3f);
  for (std::uint32_t a = 0; a < 2; ++a) {
    const Vec3f sensor{x(rng), y(rng), 2.5f};
    for (int k = 0; k < 150; ++k) {
      const Vec3f p{x(rng), y(rng), z(rng)};
      const auto base = static_cast<std::uint32_t>(m[a].positions.size());
      for (const Vec3f& d : {Vec3f{-0.15f, 0, tilt(rng)}, Vec3f{0.15f, 0.05f, 0}, Vec3f{0, 0.2f, tilt(rng)}}) {
        m[a].positions.push_back(p + d);
        m[a].sensor_positions.push_back(sensor);
      }
      m[a].triangles.push_back({base, base + 1, base + 2});
    }
  }
  add_patch(m[0], -4, 20, -6, 6, 0.0, 0.6, {8, 0, 2.5f});
  add_patch(m[2], -4, 20, -6, 6, 0.02, newer_cell, {-45, 3, 12});
  for (std::uint32_t a = 0; a < 3; ++a) finish(m[a], a);
  return m;
}

TEST(Conflicts, FlagsEqualBruteForceUnderLongSlantedEmptySpaces) {
  // The newer empty spaces are indexed whole, cut into slabs, or as the search measures (a
  // coarse newer ground: many candidates per empty space; a fine one: few).
  for (const double newer_cell : {1.0, 0.4}) {
    std::mt19937 rng(5);
    const std::vector<Mesh> meshes = facets_under_slanted_rays(rng, newer_cell);
    const std::vector<TimePoint> dates{day(0), day(10), day(40)};
    ChangeParams params;
    const ChangeResult r = detect(meshes, dates, params);
    const change_detail::TriangleFrames f = change_detail::prepare_triangles({meshes, dates}, params);
    const change_detail::PartnerBits partners = change_detail::partner_bits(f, r.consistent_pairs);
    std::vector<std::uint8_t> conflicting(f.size(), 0), refutes(f.size(), 0);
    for (std::size_t t = 0; t < f.size(); ++t) {
      for (std::size_t j = 0; j < f.acquisitions(); ++j) {
        if (!(f.date_of(t) < f.dates[j]) || partners.has(t, j)) continue;
        for (std::size_t u = f.index.offsets[j]; u < f.index.offsets[j + 1]; ++u) {
          if (f.empty_scale[u] > 0 && triangle_intersects_tetrahedron(f.corners(t), f.empty_space(u))) {
            conflicting[t] = 1;
            refutes[u] = 1;
          }
        }
      }
    }
    // Enough of each kind that a search missing some would show.
    EXPECT_GT(std::count(conflicting.begin(), conflicting.end(), 1), 40);
    EXPECT_GT(std::count(conflicting.begin(), conflicting.begin() + 300, 0), 40);
    EXPECT_GT(std::count(refutes.begin(), refutes.end(), 1), 20);
    std::vector<std::uint8_t> found(f.size(), 0);
    for (std::size_t t = 0; t < f.size(); ++t) found[t] = r.state[t] == TriangleState::conflicting ? 1 : 0;
    EXPECT_EQ(found, conflicting);
    EXPECT_EQ(r.refutes, refutes);
    for (const bool prefilter : {true, false}) {
      params.prefilter = prefilter;
      ChangeStats stats;
      const std::vector<OccupancyGrid> grids =
          change_detail::build_empty_space_grids(f, params, change_detail::asked_voxels(f, params.voxel_size), stats);
      for (const auto cut : {change_detail::SlabCut::never, change_detail::SlabCut::always}) {
        const change_detail::ConflictFlags flags =
            change_detail::find_conflicts(f, partners, grids, params, stats, cut);
        EXPECT_EQ(flags.conflicting, conflicting) << "prefilter " << prefilter << ", cut " << int(cut);
        EXPECT_EQ(flags.refutes, refutes) << "prefilter " << prefilter << ", cut " << int(cut);
      }
    }
  }
}

// ---- time series and policies ----------------------------------------------------------

TEST(TimeSeries, FirstAndLastSeenSpanPartnersAndDecideSustainability) {
  std::vector<Mesh> m(3);
  const Vec3f s{1, -3, 2.5f};
  add_patch(m[0], 0, 2, 0, 2, 0, 0.2, s);  // ground, three times
  add_patch(m[1], 0, 2, 0, 2, 0, 0.2, s);
  add_patch(m[2], 0, 2, 0, 2, 0, 0.2, s);
  add_patch(m[1], 5, 6, 0, 1, 0, 0.2, s);  // a patch seen only in the middle pass, not looked at later
  add_patch(m[2], 8, 9, 0, 1, 0, 0.2, s);  // a patch seen only in the last pass
  for (std::uint32_t a = 0; a < 3; ++a) finish(m[a], a);
  const std::vector<TimePoint> dates{day(0), day(20), day(45)};
  const std::size_t ground = 200;
  for (UnconfirmedPolicy policy :
       {UnconfirmedPolicy::drop, UnconfirmedPolicy::keep_unobserved, UnconfirmedPolicy::keep}) {
    ChangeParams p;
    p.unconfirmed = policy;
    const ChangeResult r = detect(m, dates, p);
    for (std::size_t t = 0; t < ground; ++t) {
      EXPECT_EQ(r.first_seen[t], day(0));
      EXPECT_EQ(r.last_seen[t], day(45));
      EXPECT_EQ(r.sustainable[t], 1);
      EXPECT_EQ(r.kept[t], 1);
    }
    const std::size_t lone = r.index.offsets[1] + ground, last_only = r.index.offsets[2] + ground;
    EXPECT_EQ(r.state[lone], TriangleState::single);
    EXPECT_EQ(r.first_seen[lone], day(20));
    EXPECT_EQ(r.sustainable[lone], 0);
    EXPECT_EQ(r.sustainable[last_only], 0);
    const std::uint8_t expected = policy == UnconfirmedPolicy::drop ? 0 : 1;
    EXPECT_EQ(r.kept[lone], expected) << unconfirmed_policy_name(policy);
    EXPECT_EQ(r.kept[last_only], expected) << unconfirmed_policy_name(policy);
  }
}

TEST(TimeSeries, KeepUnobservedDropsWhatANewerPassLookedAtWithoutConfirming) {
  std::vector<Mesh> m(2);
  const Vec3f s{1, -3, 2.5f};
  add_patch(m[0], 0, 2, 0, 2, 0.05, 0.2, s);  // 5 cm above the newer ground:
  add_patch(m[1], 0, 2, 0, 2, 0.0, 0.2, s);
  finish(m[0], 0);
  finish(m[1], 1);
  ChangeParams p;
  p.distance_threshold = 0.02;  // too far to be the same surface, within the conflict margin
  const ChangeResult r = detect(m, {day(0), day(10)}, p);
  for (std::size_t t = 0; t < m[0].triangle_count(); ++t) {
    EXPECT_EQ(r.state[t], TriangleState::single);
    EXPECT_EQ(r.kept[t], 0) << t;  // the newer pass's empty space reaches its voxels
  }
  p.unconfirmed = UnconfirmedPolicy::keep;
  EXPECT_EQ(detect(m, {day(0), day(10)}, p).kept[0], 1);
}

// ---- on a simulated street: pre-filter and threads change nothing ------------------------

std::vector<Mesh> simulated_street(std::vector<TimePoint>& dates) {
  StreetParams street;
  street.length = 30.0f;
  const Scene scene = make_street_scene(street);
  ScannerParams scanner;
  std::vector<Mesh> meshes;
  for (std::size_t k = 0; k < 4; ++k) {
    const std::vector<SensorGrid> grids = scan_epoch(scene, k, scanner);
    Mesh m = mesh_sensor_grid(grids.front(), {}, static_cast<std::uint32_t>(k)).mesh;
    meshes.push_back(std::move(m));
    dates.push_back(scene.epochs[k].date);
  }
  return meshes;
}

void expect_same(const ChangeResult& a, const ChangeResult& b) {
  EXPECT_EQ(a.consistent_pairs.unpacked(), b.consistent_pairs.unpacked());
  EXPECT_EQ(a.state, b.state);
  EXPECT_EQ(a.kept, b.kept);
  EXPECT_EQ(a.refutes, b.refutes);
  EXPECT_EQ(a.first_seen, b.first_seen);
  EXPECT_EQ(a.last_seen, b.last_seen);
}

TEST(DetectChanges, PrefilterAndThreadCountNeverChangeTheResult) {
  std::vector<TimePoint> dates;
  const std::vector<Mesh> meshes = simulated_street(dates);
  ChangeParams with, without;
  without.prefilter = false;
  const ChangeResult a = detect(meshes, dates, with), b = detect(meshes, dates, without);
  expect_same(a, b);
  EXPECT_GT(a.stats.prefilter_skipped, 0u);
  // Fewer candidates reach the search (its exact tests are no measure: with many candidates
  // the empty spaces are indexed by slabs, which leave out more pairs before the exact test).
  EXPECT_LT(a.stats.conflict_candidates - a.stats.prefilter_skipped,
            b.stats.conflict_candidates - b.stats.prefilter_skipped);
  EXPECT_GT(std::count(a.state.begin(), a.state.end(), TriangleState::conflicting), 100);
  const StateCounts counts = count_states(a, a.index.offsets[1], a.index.offsets[2]);
  const auto from = a.state.begin() + static_cast<std::ptrdiff_t>(a.index.offsets[1]);
  const auto to = a.state.begin() + static_cast<std::ptrdiff_t>(a.index.offsets[2]);
  EXPECT_EQ(counts.state[1], static_cast<std::uint64_t>(std::count(from, to, TriangleState::conflicting)));
  EXPECT_EQ(counts.state[0] + counts.state[1] + counts.state[2], a.index.offsets[2] - a.index.offsets[1]);
  EXPECT_EQ(counts.kept, static_cast<std::uint64_t>(std::count(a.kept.begin() + (from - a.state.begin()),
                                                               a.kept.begin() + (to - a.state.begin()), 1)));
  const ThreadLimit one(1);
  expect_same(a, detect(meshes, dates, with));
}

// ---- triangle uses: what a tile asks of its own triangles and of its copies ---------------

/// Per global triangle, its corners' x extent.
std::vector<std::pair<double, double>> x_extents(const std::vector<Mesh>& meshes) {
  std::vector<std::pair<double, double>> out;
  for (const Mesh& m : meshes) {
    for (std::size_t t = 0; t < m.triangle_count(); ++t) {
      const auto c = m.corners(t);
      out.emplace_back(std::min({c[0].x, c[1].x, c[2].x}), std::max({c[0].x, c[1].x, c[2].x}));
    }
  }
  return out;
}

TEST(TriangleUses, ContextTrianglesRaiseNoRefutesAndTwoHalvesAddUpToTheWhole) {
  std::vector<TimePoint> dates;
  const std::vector<Mesh> meshes = simulated_street(dates);
  const ChangeResult whole = detect(meshes, dates);
  const auto extents = x_extents(meshes);
  const double middle = 0.5 * (extents.front().first + extents.front().second);
  std::vector<TriangleUse> left(extents.size()), right(extents.size());
  for (std::size_t g = 0; g < extents.size(); ++g) {
    const bool is_left = extents[g].first + extents[g].second < 2 * middle;
    left[g] = is_left ? TriangleUse::labelled : TriangleUse::context;
    right[g] = is_left ? TriangleUse::context : TriangleUse::labelled;
  }
  const ChangeResult a = detect_changes({meshes, dates, left}, {}), b = detect_changes({meshes, dates, right}, {});
  for (const ChangeResult* half : {&a, &b}) {
    EXPECT_EQ(half->consistent_pairs.unpacked(), whole.consistent_pairs.unpacked());
    EXPECT_EQ(half->state, whole.state);
    EXPECT_EQ(half->kept, whole.kept);
    EXPECT_NE(half->refutes, whole.refutes);  // each half misses the other's refutations
  }
  std::vector<std::uint8_t> either(whole.refutes.size());
  for (std::size_t g = 0; g < either.size(); ++g) either[g] = a.refutes[g] | b.refutes[g];
  EXPECT_EQ(either, whole.refutes);
}

TEST(TriangleUses, TilesOfOwnedHaloAndEmptySpaceTrianglesLabelLikeTheWhole) {
  // Three tiles across the street, as the tiler cuts them: a triangle is labelled in the tile
  // holding its centroid, context where its box lies within the halo, and only lends its empty
  // space elsewhere. Each triangle's labels from its own tile, and its refutes from all tiles
  // together, are the untiled ones.
  std::vector<TimePoint> dates;
  const std::vector<Mesh> meshes = simulated_street(dates);
  const ChangeResult whole = detect(meshes, dates);
  const auto extents = x_extents(meshes);
  double lo = extents.front().first, hi = extents.front().second;
  for (const auto& [a, b] : extents) {
    lo = std::min(lo, a);
    hi = std::max(hi, b);
  }
  constexpr int kTiles = 3;
  constexpr double kHalo = 2.0;
  const double size = (hi - lo) / kTiles + 1e-6;
  const auto tile_of = [&](std::size_t g) {
    return std::min(kTiles - 1, static_cast<int>((0.5 * (extents[g].first + extents[g].second) - lo) / size));
  };
  const auto near = [&](std::size_t g, int k) {
    return extents[g].second >= lo + k * size - kHalo && extents[g].first <= lo + (k + 1) * size + kHalo;
  };
  // The halo holds every partner of a tile's own triangles: they ask in that tile.
  for (const auto& [g, h] : whole.consistent_pairs) {
    ASSERT_TRUE(near(h, tile_of(g)) && near(g, tile_of(h))) << g << " " << h;
  }
  std::vector<std::uint8_t> refutes(whole.refutes.size(), 0);
  std::size_t empty_space_triangles = 0;
  for (int k = 0; k < kTiles; ++k) {
    std::vector<TriangleUse> uses(extents.size());
    for (std::size_t g = 0; g < uses.size(); ++g) {
      uses[g] = tile_of(g) == k ? TriangleUse::labelled : near(g, k) ? TriangleUse::context : TriangleUse::empty_space;
      empty_space_triangles += uses[g] == TriangleUse::empty_space ? 1 : 0;
    }
    const ChangeResult tile = detect_changes({meshes, dates, uses}, {});
    for (std::size_t g = 0; g < uses.size(); ++g) {
      refutes[g] |= tile.refutes[g];
      if (uses[g] == TriangleUse::empty_space) {
        ASSERT_EQ(tile.kept[g], 0) << g;
        ASSERT_NE(tile.state[g], TriangleState::conflicting) << g;
      }
      if (uses[g] != TriangleUse::labelled) continue;
      ASSERT_EQ(tile.state[g], whole.state[g]) << g;
      ASSERT_EQ(tile.kept[g], whole.kept[g]) << g;
      ASSERT_EQ(tile.sustainable[g], whole.sustainable[g]) << g;
      ASSERT_EQ(tile.first_seen[g], whole.first_seen[g]) << g;
      ASSERT_EQ(tile.last_seen[g], whole.last_seen[g]) << g;
    }
  }
  EXPECT_GT(empty_space_triangles, extents.size());  // most of the street lends only its empty space
  EXPECT_EQ(refutes, whole.refutes);
  EXPECT_GT(std::count(refutes.begin(), refutes.end(), 1), 100);
}

TEST(TriangleUses, AUseForEachTriangleOrNone) {
  std::vector<TimePoint> dates;
  const std::vector<Mesh> meshes = simulated_street(dates);
  const std::vector<TriangleUse> one(1, TriangleUse::labelled);
  EXPECT_THROW((void)detect_changes({meshes, dates, one}, {}), ProcessingError);
}

TEST(EmptySpaceGrids, MarkedOnlyWhereAskedTheyAnswerEveryQuestionAsIfMarkedEverywhere) {
  std::vector<TimePoint> dates;
  const std::vector<Mesh> meshes = simulated_street(dates);
  const ChangeParams params;
  const change_detail::TriangleFrames f = change_detail::prepare_triangles({meshes, dates}, params);
  ChangeStats everywhere_stats, asked_stats;
  const std::vector<OccupancyGrid> everywhere =
      change_detail::build_empty_space_grids(f, params, VoxelMask(), everywhere_stats);
  const std::vector<OccupancyGrid> asked =
      change_detail::build_empty_space_grids(f, params, change_detail::asked_voxels(f, params.voxel_size), asked_stats);
  EXPECT_LT(asked_stats.marked_voxels * 2, everywhere_stats.marked_voxels);  // the mask spares most marks
  // The questions the pre-filter and the unconfirmed policy ask: a triangle's box, of a grid newer.
  std::size_t questions = 0, yes = 0;
  for (std::size_t g = 0; g < f.size(); ++g) {
    for (std::size_t j = 0; j < f.acquisitions(); ++j) {
      if (!(f.date_of(g) < f.dates[j])) continue;
      const Box3f& b = f.bounds(g);
      const bool answer = everywhere[j].any_in_box(b.min, b.max);
      ASSERT_EQ(asked[j].any_in_box(b.min, b.max), answer) << "triangle " << g << ", grid " << j;
      ++questions;
      yes += answer ? 1 : 0;
    }
  }
  EXPECT_GT(yes, questions / 10);
  EXPECT_LT(yes, questions);
}

TEST(DetectChanges, NoMeshesGiveAnEmptyResult) {
  const ChangeResult r = detect_changes({{}, {}}, ChangeParams{});
  EXPECT_EQ(r.index.size(), 0u);
  EXPECT_TRUE(r.kept.empty());
  EXPECT_TRUE(r.consistent_pairs.empty());
}

TEST(DetectChanges, RejectsMeshesInDifferentFramesOrWithoutSensors) {
  std::vector<Mesh> m = wall_then_gone();
  m[1].origin = {1, 0, 0};
  EXPECT_THROW(detect(m, {day(0), day(1)}), ProcessingError);
  m = wall_then_gone();
  m[1].sensor_positions.clear();
  EXPECT_THROW(detect(m, {day(0), day(1)}), ProcessingError);
  EXPECT_THROW(detect(wall_then_gone(), {day(0)}), ProcessingError);
}

}  // namespace
}  // namespace citymesh
