// SPDX-License-Identifier: MIT
// Stitching an output part by part: each part's triangles once, with the parts stitched before
// as frozen surroundings (StitchSurroundings). What is frozen must come out unchanged, and the
// seams must close about as well as when the whole output is stitched at once.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <set>

#include "citymesh/core/geometry.h"
#include "citymesh/mosaic/stitch.h"
#include "stitch_fixtures.h"

namespace citymesh {
namespace {

using test::add_grid;
using test::contains_all;
using test::corners_of;
using test::Corners;
using test::flipped_or_flat;
using test::triangles_of;
using test::non_manifold_edges;
using test::repeated_directed_edges;

/// Three sources with every kind of seam, all crossing the line y = 0.5: source 0 and,
/// 4 cm beyond its side x = 2, a coarser source 1 (zippered); 1.5 cm beyond source 1's side
/// x = 4, source 2 (snapped); and a small piece of source 3 lying 5 cm over source 0 (clipped).
MergedMesh scene() {
  MergedMesh m;
  add_grid(m, 0, 0, 20, 10, 0.1f, 0, 0);
  add_grid(m, 2.04f, 0.013f, 18, 9, 0.11f, 1, 0.01f);
  add_grid(m, 4.035f, 0, 10, 10, 0.1f, 2, 0.01f);
  add_grid(m, 0.85f, 0.2f, 6, 5, 0.1f, 3, 0.05f);
  return m;
}

const StitchParams kParams{.snap = 0.02, .reach = 0.2, .weld = 0.005, .clip = 0.1, .gap = 0.1};

constexpr auto kFree = static_cast<std::uint8_t>(VertexRole::free);
constexpr auto kDone = static_cast<std::uint8_t>(VertexRole::done);
constexpr auto kLater = static_cast<std::uint8_t>(VertexRole::later);

/// Vertex roles for a pass over the triangles `of_part` picks: the others' vertices are
/// `others` (done or later), those of the part alone free.
template <class OfPart>
std::vector<std::uint8_t> roles_for(const MergedMesh& m, OfPart of_part, std::uint8_t others) {
  std::vector<std::uint8_t> roles(m.mesh.vertex_count(), kFree);
  for (std::size_t t = 0; t < m.mesh.triangle_count(); ++t) {
    if (of_part(t)) continue;
    for (const std::uint32_t v : m.mesh.triangles[t]) roles[v] = others;
  }
  return roles;
}

double centroid_y(const MergedMesh& m, std::size_t t) {
  const TriangleCorners c = m.mesh.corners(t);
  return (c[0].y + c[1].y + c[2].y) / 3;
}

TEST(StitchParts, TwoPartsLeaveWhatIsFrozenAsItWasAndCloseTheSeamsAsTheWholeDoes) {
  const MergedMesh input = scene();
  const std::vector<std::uint64_t> sizes = source_sizes(input);
  MergedMesh whole = input;
  const StitchStats at_once = stitch(whole, kParams);

  // Part 1: the triangles below y = 0.5, with those above as they are (raw) around them.
  const auto above = [&](std::size_t t) { return centroid_y(input, t) >= 0.5; };
  MergedMesh m = input;
  const std::vector<std::uint8_t> roles1 = roles_for(input, [&](std::size_t t) { return !above(t); }, kLater);
  const std::multiset<Corners> raw_above = triangles_of(input, above);
  const StitchStats first = stitch(m, kParams, {.vertex_roles = roles1, .source_sizes = sizes});
  EXPECT_GT(first.strips + first.vertices_snapped + first.triangles_clipped, 0u);
  ASSERT_TRUE(contains_all(triangles_of(m, [](std::size_t) { return true; }), raw_above))
      << "part 1 changed a frozen triangle";

  // Part 2: the raw triangles above, with part 1's output frozen around them.
  std::multiset<Corners> remaining_raw = raw_above;
  std::vector<std::uint8_t> is_raw_above(m.mesh.triangle_count(), 0);
  for (std::size_t t = 0; t < m.mesh.triangle_count(); ++t) {
    const auto it = remaining_raw.find(corners_of(m, t));
    if (m.source_acq[t] == kNoSource || it == remaining_raw.end()) continue;
    remaining_raw.erase(it);
    is_raw_above[t] = 1;
  }
  ASSERT_TRUE(remaining_raw.empty());
  const auto part1 = [&](std::size_t t) { return is_raw_above[t] == 0; };
  const std::vector<std::uint8_t> roles2 = roles_for(m, [&](std::size_t t) { return !part1(t); }, kDone);
  const std::multiset<Corners> part1_output = triangles_of(m, part1);
  const StitchStats second = stitch(m, kParams, {.vertex_roles = roles2, .source_sizes = sizes});
  EXPECT_GT(second.strips + second.vertices_snapped, 0u);
  ASSERT_TRUE(contains_all(triangles_of(m, [](std::size_t) { return true; }), part1_output))
      << "part 2 changed part 1's output";

  EXPECT_EQ(non_manifold_edges(m.mesh), 0u);
  EXPECT_EQ(repeated_directed_edges(m.mesh), 0u);
  EXPECT_EQ(flipped_or_flat(m.mesh), 0u);
  EXPECT_EQ(non_manifold_edges(whole.mesh), 0u);
  EXPECT_EQ(repeated_directed_edges(whole.mesh), 0u);
  // Unstitched: the outline of each piece, about 24 m; at once: mostly the union's outline.
  const double closed_at_once = at_once.open_boundary_before - at_once.open_boundary_after;
  const double closed_in_parts = first.open_boundary_before - second.open_boundary_after;
  EXPECT_GT(closed_at_once, 5.0);
  EXPECT_GT(closed_in_parts, 0.98 * closed_at_once)
      << "open after stitching at once: " << at_once.open_boundary_after
      << " m, in two parts: " << second.open_boundary_after << " m";
  EXPECT_EQ(second.open_boundary_after, open_boundary_length(m.mesh));
}

TEST(StitchParts, AFreeVertexSnapsOntoAFrozenOne) {
  // Two sources whose facing sides lie 1.5 cm apart; source 1's vertices are frozen: source
  // 0's boundary vertices go onto them (not half way), and no frozen vertex moves.
  MergedMesh m;
  add_grid(m, 0, 0, 10, 10, 0.1f, 0, 0);
  add_grid(m, 1.015f, 0, 10, 10, 0.1f, 1, 0.005f);
  const std::vector<std::uint8_t> frozen = roles_for(m, [&](std::size_t t) { return m.source_acq[t] == 0; }, kDone);
  const std::vector<Vec3f> before = m.mesh.positions;
  const StitchStats s = stitch(m, {.snap = 0.05, .reach = 0.1, .weld = 0.005}, {.vertex_roles = frozen});
  EXPECT_GE(s.vertices_snapped, 10u);
  EXPECT_EQ(s.rejected, 0u);  // a free vertex met first goes to the frozen one (not refused)
  for (std::size_t v = 0; v < frozen.size(); ++v) {
    if (frozen[v] != 0) {
      EXPECT_EQ(m.mesh.positions[v], before[v]) << "frozen vertex " << v << " moved";
    }
  }
  // Source 0's side x = 1 is now at x = 1.015, on source 1's vertices.
  std::size_t moved_onto = 0;
  for (std::size_t t = 0; t < m.mesh.triangle_count(); ++t) {
    if (m.source_acq[t] != 0) continue;
    for (const std::uint32_t v : m.mesh.triangles[t]) moved_onto += frozen[v] != 0 ? 1 : 0;
  }
  EXPECT_GE(moved_onto, 20u);
  EXPECT_LT(s.open_boundary_after, s.open_boundary_before - 1.9);
  EXPECT_EQ(non_manifold_edges(m.mesh), 0u);
  EXPECT_EQ(repeated_directed_edges(m.mesh), 0u);
}

TEST(StitchParts, ClippingCutsOnlyFreeTriangles) {
  // Source 0 (smaller) lies 5 cm over source 1 (larger): it yields, unless it is frozen; a
  // frozen larger source still cuts the free smaller one.
  const auto pieces = [] {
    MergedMesh m;
    add_grid(m, 0, 0, 10, 10, 0.1f, 1, 0);
    add_grid(m, 0.85f, 0.2f, 6, 4, 0.1f, 0, 0.05f);
    return m;
  };
  // Stitched with the triangles of source `done` as output stitched before.
  const auto with_done = [&](std::int32_t done) {
    MergedMesh m = pieces();
    const std::vector<std::uint8_t> roles = roles_for(m, [&](std::size_t t) { return m.source_acq[t] != done; }, kDone);
    return stitch(m, {.snap = 0.02, .reach = 0.02, .weld = 0.005, .clip = 0.1}, {.vertex_roles = roles});
  };
  const StitchStats a = with_done(0);
  EXPECT_EQ(a.triangles_clipped + a.triangles_uncovered, 0u);
  const StitchStats b = with_done(1);
  EXPECT_GT(b.triangles_clipped + b.triangles_uncovered, 0u);

  // Precedence follows the sizes given: with source 0 said to be the larger, source 1 yields.
  MergedMesh sized = pieces();
  const std::vector<std::uint64_t> sizes{1000, 200};
  const StitchStats c =
      stitch(sized, {.snap = 0.02, .reach = 0.02, .weld = 0.005, .clip = 0.1}, {.source_sizes = sizes});
  double source1_area = 0;
  for (std::size_t t = 0; t < sized.mesh.triangle_count(); ++t) {
    const TriangleCorners k = sized.mesh.corners(t);
    if (sized.source_acq[t] == 1) source1_area += norm(cross(k[1] - k[0], k[2] - k[0])) / 2;
  }
  EXPECT_GT(c.triangles_clipped + c.triangles_uncovered, 0u);
  EXPECT_LT(source1_area, 1.0 - 0.03);  // the 0.15 m x 0.4 m under source 0, about
}

}  // namespace
}  // namespace citymesh
