// SPDX-License-Identifier: MIT
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <random>

#include "citymesh/core/error.h"
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

TEST(SeenThrough, FollowsGrazingRaysFarFromTheSurfaceTheyEndOn) {
  // Pass 1 saw a floor triangle around the origin from 30 m away, 1 m up: its ray to the
  // floor passes half a metre over the floor 15 m from it, far beyond the triangle's own box.
  const std::vector<std::array<Vec3f, 3>> floor{{Vec3f{-1, -1, 0}, Vec3f{1, -1, 0}, Vec3f{0, 1, 0}}};
  const Vec3f side{30, 0, 1};
  const std::vector<Mesh> meshes{triangles_seen_from({around({15.0f, 0.0f, 0.5f}), around({15.0f, 3.0f, 0.5f})},
                                                     {side, side}),
                                 triangles_seen_from(floor, {side})};
  GlobalTriangles index;
  index.offsets = {0, 2, 3};
  EXPECT_EQ(seen_through(meshes, index, std::vector<std::uint32_t>{0, 1}, {.margin = 0.1, .depth = 1.0}),
            (std::vector<std::uint8_t>{1, 0}))
      << "on the ray, and 3 m beside it";
}

/// Brute force: p inside the tetrahedron (v, q) when its barycentric coordinates are all
/// positive, and between margin and depth from q's plane.
bool brute_force_seen(const Vec3d& p, const Vec3d& v, const std::array<Vec3d, 3>& q, const SeenThroughParams& params) {
  const auto det = [](const Vec3d& a, const Vec3d& b, const Vec3d& c) { return dot(a, cross(b, c)); };
  const double whole = det(q[0] - v, q[1] - v, q[2] - v);
  if (whole == 0) return false;
  const double b0 = det(p - v, q[1] - v, q[2] - v) / whole, b1 = det(q[0] - v, p - v, q[2] - v) / whole,
               b2 = det(q[0] - v, q[1] - v, p - v) / whole;
  if (b0 < 0 || b1 < 0 || b2 < 0 || b0 + b1 + b2 > 1) return false;
  const Vec3d n = cross(q[1] - q[0], q[2] - q[0]) / norm(cross(q[1] - q[0], q[2] - q[0]));
  const double h = std::abs(dot(p - q[0], n));
  return h > params.margin && h <= params.depth;
}

/// Random scenes of three passes of `per_pass` small triangles each, seen from above: the
/// flags of pass 0's triangles against brute force; returns how many are seen through.
std::size_t check_random_scenes_against_brute_force(int per_pass, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-1.5f, 1.5f), corner(-0.4f, 0.4f), height(2.0f, 8.0f);
  const SeenThroughParams params{.margin = 0.1, .depth = 0.8};
  std::size_t seen_count = 0;
  for (int scene = 0; scene < 20; ++scene) {
    std::vector<Mesh> meshes;
    for (int pass = 0; pass < 3; ++pass) {
      std::vector<std::array<Vec3f, 3>> corners;
      std::vector<Vec3f> sensors;
      for (int t = 0; t < per_pass; ++t) {
        const Vec3f c{u(rng), u(rng), u(rng) * 0.3f};
        corners.push_back({c + Vec3f{corner(rng), corner(rng), corner(rng) * 0.2f},
                           c + Vec3f{corner(rng), corner(rng), corner(rng) * 0.2f},
                           c + Vec3f{corner(rng), corner(rng), corner(rng) * 0.2f}});
        sensors.push_back({u(rng) * 3, u(rng) * 3, height(rng)});
      }
      meshes.push_back(triangles_seen_from(corners, sensors));
    }
    GlobalTriangles index;
    const auto n = static_cast<std::uint32_t>(per_pass);
    index.offsets = {0, n, 2 * n, 3 * n};
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
  return seen_count;
}

TEST(SeenThrough, AgreesWithBarycentricCoordinatesOnRandomScenes) {
  EXPECT_GT(check_random_scenes_against_brute_force(60, 5), 50u) << "the scenes must exercise the positive case";
}

TEST(SeenThrough, AgreesWithBarycentricCoordinatesWhereEachEmptySpaceHoldsManyPoints) {
  // Ten times the triangles in the same volume: a run of empty spaces holds hundreds of the
  // points asked about, and each space is asked on its own.
  EXPECT_GT(check_random_scenes_against_brute_force(600, 6), 500u) << "the scenes must exercise the positive case";
}

/// Pass 0: three small triangles 0.3 m up, the first two over pass 1's 4 m x 4 m floor (in its
/// empty space, seen from 10 m above), the third beside it. Both passes kept, dates 1 and 40.
struct RaisedOverFloor {
  std::vector<Mesh> meshes;
  std::vector<TimePoint> dates{TimePoint(std::chrono::days(1)), TimePoint(std::chrono::days(40))};
  ChangeResult change;
  RaisedOverFloor() {
    const std::vector<std::array<Vec3f, 3>> floor{{Vec3f{-2, -2, 0}, Vec3f{2, -2, 0}, Vec3f{2, 2, 0}},
                                                  {Vec3f{-2, -2, 0}, Vec3f{2, 2, 0}, Vec3f{-2, 2, 0}}};
    std::vector<std::array<Vec3f, 3>> raised;
    for (const Vec3f& p : {Vec3f{0.5f, 0.5f, 0.3f}, Vec3f{-0.5f, 0.2f, 0.3f}, Vec3f{5.0f, 5.0f, 0.3f}}) {
      raised.push_back(around(p));
    }
    const Vec3f above{0, 0, 10};
    meshes = {triangles_seen_from(raised, std::vector<Vec3f>(3, above)), triangles_seen_from(floor, {above, above})};
    change.index.offsets = {0, 3, 5};
    change.kept.assign(5, 1);
  }
  [[nodiscard]] MosaicInput input() const { return {meshes, dates, &change, 0.1, {}}; }
};

TEST(FillHoles, LeavesOutWhatAnotherPassSawThrough) {
  // The selection (pass 1) is a floor seen from above; pass 0 (kept, not selected) has
  // triangles 0.3 m higher - more than the threshold away, so the fill would take them - of
  // which pass 1 saw through the first two. With sensor positions they stay out; without,
  // the fill takes them.
  RaisedOverFloor scene;
  std::vector<std::uint8_t> selected{0, 0, 0, 1, 1};
  const HoleFillCounts counts = fill_holes(scene.input(), selected);
  EXPECT_EQ(counts.added, 1u);
  EXPECT_EQ(counts.seen_through, 2u);
  EXPECT_EQ(selected, (std::vector<std::uint8_t>{0, 0, 1, 1, 1})) << "only the one beside the floor";

  // Flags already known (as the energy's) give the same fill; all clear, nothing is left out.
  const std::vector<std::uint8_t> known = seen_through(scene.meshes, scene.change.index, std::vector<std::uint32_t>{0, 1, 2, 3, 4}, {.margin = 0.1});
  std::vector<std::uint8_t> reused{0, 0, 0, 1, 1};
  const HoleFillCounts again = fill_holes(scene.input(), reused, known);
  EXPECT_EQ(reused, selected);
  EXPECT_EQ(again.seen_through, counts.seen_through);
  std::vector<std::uint8_t> unflagged{0, 0, 0, 1, 1};
  EXPECT_EQ(fill_holes(scene.input(), unflagged, std::vector<std::uint8_t>(5, 0)).added, 3u);
  std::vector<std::uint8_t> short_flags{0, 0, 0, 1, 1};
  EXPECT_THROW(fill_holes(scene.input(), short_flags, std::vector<std::uint8_t>(2, 0)), ProcessingError);

  for (Mesh& m : scene.meshes) m.sensor_positions.clear();
  std::vector<std::uint8_t> blind{0, 0, 0, 1, 1};
  EXPECT_EQ(fill_holes(scene.input(), blind).added, 3u);
}

TEST(FillHoles, NotesWhatItAddsAndWhatItLeavesOut) {
  // The same scene: the fill notes the triangle it adds and the two it leaves out, nothing
  // else; notes already raised stay; notes of the wrong length are refused.
  const RaisedOverFloor scene;
  std::vector<std::uint8_t> selected{0, 0, 0, 1, 1};
  std::vector<std::uint8_t> notes{0, 0, 0, 0, kNoteSeenThrough};
  const HoleFillCounts counts = fill_holes(scene.input(), selected, {}, &notes);
  EXPECT_EQ(notes, (std::vector<std::uint8_t>{kNoteFillLeftOut, kNoteFillLeftOut, kNoteFilled, 0, kNoteSeenThrough}));
  EXPECT_EQ(counts.added, 1u);
  EXPECT_EQ(counts.seen_through, 2u);
  std::vector<std::uint8_t> again{0, 0, 0, 1, 1}, short_notes(3, 0);
  EXPECT_THROW(fill_holes(scene.input(), again, {}, &short_notes), ProcessingError);
}

TEST(MosaicSelection, NotesCountWhatTheStatsCount) {
  // Per-triangle notes are what tiled runs add up: their counts must be the stats'.
  const RaisedOverFloor scene;
  MosaicParams params;
  params.seen_through_quality = 0.5;
  const MosaicSelection s = select_mosaic(scene.input(), params);
  ASSERT_EQ(s.notes.size(), 5u);
  const auto noted = [&](std::uint8_t bit) {
    return static_cast<std::uint64_t>(std::count_if(s.notes.begin(), s.notes.end(), [&](std::uint8_t n) { return (n & bit) != 0; }));
  };
  EXPECT_EQ(noted(kNoteSeenThrough), s.stats.seen_through);
  EXPECT_EQ(s.stats.seen_through, 2u);
  EXPECT_EQ(noted(kNoteFilled), s.stats.filled);
  EXPECT_EQ(noted(kNoteFillLeftOut), s.stats.fill_seen_through);
  for (std::size_t g = 0; g < 5; ++g) {
    if ((s.notes[g] & kNoteFilled) != 0) {
      EXPECT_EQ(s.selected[g], 1) << "a filled triangle is selected";
    }
    if ((s.notes[g] & kNoteFillLeftOut) != 0) {
      EXPECT_EQ(s.selected[g], 0) << "a left-out triangle is not";
    }
  }
  EXPECT_TRUE(select_update_model(scene.input()).notes.empty());
}

TEST(MosaicEnergy, ScalesTheQualityOfWhatAnotherPassSawThrough) {
  // Pass 0's first two triangles stand in pass 1's empty space: their quality is multiplied
  // by seen_through_quality, the others' is not, and with 1 nothing changes.
  const RaisedOverFloor scene;
  MosaicParams params;
  params.quality_weight = 2;
  params.seen_through_quality = 0.25;
  const MosaicEnergy scaled = build_mosaic_energy(scene.input(), params);
  EXPECT_EQ(scaled.stats.seen_through, 2u);
  EXPECT_EQ(scaled.quality, (std::vector<double>{-0.5, -0.5, -2, -2, -2}));
  params.seen_through_quality = 1;
  const MosaicEnergy plain = build_mosaic_energy(scene.input(), params);
  EXPECT_EQ(plain.stats.seen_through, 0u);
  EXPECT_EQ(plain.quality, (std::vector<double>(5, -2.0)));
  for (std::size_t v = 0; v < 5; ++v) {
    EXPECT_NEAR(scaled.energy.unary[v][1] - scaled.quality[v], plain.energy.unary[v][1] - plain.quality[v], 1e-12)
        << "the boundary part is untouched";
  }
}

}  // namespace
}  // namespace citymesh
