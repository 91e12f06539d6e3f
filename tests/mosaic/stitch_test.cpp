// SPDX-License-Identifier: MIT
#include "citymesh/mosaic/stitch.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <random>

#include "citymesh/core/geometry.h"
#include "clip.h"
#include "gap_fill.h"
#include "snap.h"
#include "stitch_fixtures.h"

namespace citymesh {
namespace {

using test::add_grid;
using test::non_manifold_edges;
using test::repeated_directed_edges;

/// Appends `tris` (indices into m's positions) with source `source`.
void add_triangles(MergedMesh& m, std::int32_t source, std::initializer_list<Triangle> tris) {
  for (const Triangle& t : tris) {
    m.mesh.triangles.push_back(t);
    m.mesh.triangle_ids.push_back({});
    m.source_acq.push_back(source);
    m.source_triangle.push_back(static_cast<std::int32_t>(m.source_triangle.size()));
  }
}

TEST(Stitch, ClosesTheGapBetweenTwoPiecesOfDifferentSources) {
  MergedMesh m;
  add_grid(m, 0, 0, 10, 10, 0.1f, 0);
  add_grid(m, 1.06f, 0.013f, 8, 9, 0.11f, 1, 0.01f);  // a coarser piece beside it, 6 cm away
  const double before = open_boundary_length(m.mesh);
  // Snapping only within 2 cm: the 6 cm gap is the zipper's.
  const StitchStats s = stitch(m, {.snap = 0.02, .reach = 0.2, .weld = 0.005});
  EXPECT_NEAR(s.open_boundary_before, before, 1e-9);
  EXPECT_EQ(s.vertices_snapped + s.edges_split, 0u);
  EXPECT_GE(s.strips, 1u);
  EXPECT_GT(s.triangles_added, 15u);
  EXPECT_EQ(non_manifold_edges(m.mesh), 0u);
  // The two facing sides (about 1 m each) are no longer open; the outer boundary stays.
  EXPECT_LT(s.open_boundary_after, before - 1.7);
  // The figure reported (from the incidence lists) is the one a sort of every edge gives.
  EXPECT_EQ(s.open_boundary_after, open_boundary_length(m.mesh));
  for (std::size_t t = 0; t < m.mesh.triangle_count(); ++t) {
    if (m.source_acq[t] != kNoSource) continue;
    const Triangle& tri = m.mesh.triangles[t];
    const Vec3d a(m.mesh.positions[tri[0]]), b(m.mesh.positions[tri[1]]), c(m.mesh.positions[tri[2]]);
    EXPECT_GT(cross(b - a, c - a).z, 0) << "strip triangle " << t << " is flipped or flat";
  }
}

TEST(Stitch, SnapsNearlyCoincidentBoundariesIntoSharedEdges) {
  // Two sources whose facing sides lie 1.5 cm apart with different vertex spacings: the seam
  // must close by shared vertices (no strip of slivers), leaving only the outer boundary.
  MergedMesh m;
  add_grid(m, 0, 0, 10, 10, 0.1f, 0);
  add_grid(m, 1.015f, 0.0f, 7, 7, 0.1428571f, 1, 0.005f);
  const std::size_t pieces = m.mesh.triangle_count();
  const double before = open_boundary_length(m.mesh);
  const StitchStats s = stitch(m, {.snap = 0.05, .reach = 0.1, .weld = 0.005});
  EXPECT_GT(s.vertices_snapped, 0u);
  EXPECT_GT(s.edges_split, 0u);
  EXPECT_EQ(non_manifold_edges(m.mesh), 0u);
  EXPECT_EQ(repeated_directed_edges(m.mesh), 0u);
  // Outer boundary: 2 x (1 + 1) + 2 x 1 ... of the union, a 2 m x 1 m rectangle, about 6 m.
  EXPECT_LT(s.open_boundary_after, 6.1);
  EXPECT_NEAR(s.open_boundary_after, before - 2.0, 0.1);
  EXPECT_EQ(s.open_boundary_after, open_boundary_length(m.mesh));
  std::size_t provenance_kept = 0;
  for (std::size_t t = 0; t < m.mesh.triangle_count(); ++t) {
    const Triangle& tri = m.mesh.triangles[t];
    const Vec3d a(m.mesh.positions[tri[0]]), b(m.mesh.positions[tri[1]]), c(m.mesh.positions[tri[2]]);
    EXPECT_GT(cross(b - a, c - a).z, 1e-6) << "triangle " << t << " is flipped or flat";
    provenance_kept += m.source_acq[t] != kNoSource ? 1 : 0;
  }
  EXPECT_GE(provenance_kept, pieces);  // split pieces keep their source
}

TEST(Stitch, LeavesPiecesOfOneSourceAndFarPiecesAlone) {
  MergedMesh m;
  add_grid(m, 0, 0, 5, 5, 0.1f, 0);
  add_grid(m, 0.56f, 0, 5, 5, 0.1f, 0);  // same source: a real gap in that scan
  add_grid(m, 2.0f, 0, 5, 5, 0.1f, 1);   // another source, far away
  const std::size_t triangles = m.mesh.triangle_count();
  const StitchStats s = stitch(m, {.snap = 0.2, .reach = 0.2, .weld = 0.005});
  EXPECT_EQ(s.strips, 0u);
  EXPECT_EQ(s.vertices_snapped + s.edges_split, 0u);
  EXPECT_EQ(m.mesh.triangle_count(), triangles);
  EXPECT_NEAR(s.open_boundary_after, s.open_boundary_before, 1e-9);
}

/// Area of the triangles of `source`.
double area_of(const MergedMesh& m, std::int32_t source) {
  double total = 0;
  for (std::size_t t = 0; t < m.mesh.triangle_count(); ++t) {
    if (m.source_acq[t] != source) continue;
    const TriangleCorners c = m.mesh.corners(t);
    total += 0.5 * norm(cross(c[1] - c[0], c[2] - c[0]));
  }
  return total;
}

/// A 1 m x 1 m grid of source 1 and, 5 cm above it, a 0.6 m x 0.4 m grid of source 0 (fewer
/// triangles: it yields) reaching 15 cm over its side x = 1.
MergedMesh overlapping_pieces() {
  MergedMesh m;
  add_grid(m, 0, 0, 10, 10, 0.1f, 1);
  add_grid(m, 0.85f, 0.2f, 6, 4, 0.1f, 0, 0.05f);
  for (const Vec3f& p : m.mesh.positions) {
    m.mesh.sensor_positions.push_back(p + Vec3f{0, 0, 10});
    m.mesh.times.push_back(100.0 + p.x);
  }
  return m;
}

TEST(Clip, CutsTheSmallerPieceBackToWhereTheLargerEnds) {
  MergedMesh m = overlapping_pieces();
  const std::size_t large = 200;
  const mosaic_detail::ClipStats s = mosaic_detail::clip_overlaps(m, {.tolerance = 0.1});
  EXPECT_GT(s.triangles_cut, 0u);
  EXPECT_EQ(s.triangles_removed, 8u);  // the column of cells between x = 0.85 and 0.95
  EXPECT_EQ(std::count(m.source_acq.begin(), m.source_acq.end(), 1), static_cast<std::ptrdiff_t>(large));
  EXPECT_NEAR(area_of(m, 1), 1.0, 1e-5);
  // Ground truth: what is left of source 0 is the rectangle [1, 1.45] x [0.2, 0.6].
  EXPECT_NEAR(area_of(m, 0), 0.45 * 0.4, 1e-4);
  MergedMesh small;
  for (std::size_t t = 0; t < m.mesh.triangle_count(); ++t) {
    if (m.source_acq[t] != 0) continue;
    small.mesh.triangles.push_back(m.mesh.triangles[t]);
    for (const std::uint32_t v : m.mesh.triangles[t]) {
      EXPECT_GE(m.mesh.positions[v].x, 1.0f - 1e-4f) << "a corner is still over the larger piece";
    }
  }
  small.mesh.positions = m.mesh.positions;
  // Conforming: the neighbours of a cut edge cut it at the same vertex, so the part left has
  // no crack inside: its open boundary is the rectangle's perimeter.
  EXPECT_NEAR(open_boundary_length(small.mesh), 2 * (0.45 + 0.4), 1e-3);
  EXPECT_EQ(non_manifold_edges(m.mesh), 0u);
  EXPECT_EQ(repeated_directed_edges(m.mesh), 0u);
  for (std::size_t t = 0; t < m.mesh.triangle_count(); ++t) {
    const TriangleCorners c = m.mesh.corners(t);
    EXPECT_GT(cross(c[1] - c[0], c[2] - c[0]).z, 1e-6) << "triangle " << t << " is flipped or flat";
  }
  // New vertices interpolate every attribute.
  ASSERT_NO_THROW(m.mesh.check_invariants());
  for (std::size_t v = 0; v < m.mesh.vertex_count(); ++v) {
    EXPECT_NEAR(m.mesh.sensor_positions[v].z - m.mesh.positions[v].z, 10.0f, 1e-4f);
    EXPECT_NEAR(m.mesh.times[v], 100.0 + m.mesh.positions[v].x, 1e-5);
  }
}

TEST(Clip, OnEqualSizesTheEarlierSourceYields) {
  MergedMesh m;
  add_grid(m, 0, 0, 4, 4, 0.1f, 3);
  add_grid(m, 0.35f, 0, 4, 4, 0.1f, 2, 0.03f);
  mosaic_detail::clip_overlaps(m, {.tolerance = 0.1});
  EXPECT_NEAR(area_of(m, 3), 0.16, 1e-5);
  EXPECT_NEAR(area_of(m, 2), 0.35 * 0.4, 1e-4);
}

TEST(Clip, LeavesCrossingAndDistantSurfacesAlone) {
  MergedMesh m;
  add_grid(m, 0, 0, 10, 10, 0.1f, 1);
  add_grid(m, 0.3f, 0.3f, 3, 3, 0.1f, 0, 0.15f);  // parallel but farther than the tolerance
  // A wall standing on the grid (90 degrees): it meets the grid; it does not lie over it.
  const auto base = static_cast<std::uint32_t>(m.mesh.positions.size());
  for (const Vec3f p : {Vec3f{0.5f, 0.1f, 0.0f}, Vec3f{0.5f, 0.9f, 0.0f}, Vec3f{0.5f, 0.9f, 0.5f}, Vec3f{0.5f, 0.1f, 0.5f}}) {
    m.mesh.positions.push_back(p);
  }
  for (const Triangle& t : {Triangle{base, base + 1, base + 2}, Triangle{base, base + 2, base + 3}}) {
    m.mesh.triangles.push_back(t);
    m.mesh.triangle_ids.push_back({});
    m.source_acq.push_back(0);
    m.source_triangle.push_back(0);
  }
  const MergedMesh before = m;
  const mosaic_detail::ClipStats s = mosaic_detail::clip_overlaps(m, {.tolerance = 0.1});
  EXPECT_EQ(s.triangles_cut + s.triangles_removed + s.vertices_added, 0u);
  EXPECT_EQ(m.mesh.triangles, before.mesh.triangles);
}

/// A 1 m x 1 m grid of source 1 and a 0.4 m x 0.4 m grid of source 0 rising from it at
/// `degrees`, from 2 cm above it: another mesh's chamfer over the same corner of a facade (45
/// degrees), or a facet one pass strung across a recess (steeper).
MergedMesh slanted_piece(double degrees = 45) {
  MergedMesh m;
  add_grid(m, 0, 0, 10, 10, 0.1f, 1);
  const std::size_t first = m.mesh.positions.size();
  add_grid(m, 0.3f, 0.3f, 4, 4, 0.1f, 0);
  const double angle = degrees * std::numbers::pi / 180.0;
  for (std::size_t v = first; v < m.mesh.positions.size(); ++v) {
    Vec3f& p = m.mesh.positions[v];
    const double along = p.x - 0.3f;
    p = {static_cast<float>(0.3 + along * std::cos(angle)), p.y, static_cast<float>(0.02 + along * std::sin(angle))};
  }
  return m;
}

TEST(Clip, CutsFacetsUpTo80DegreesSteepByDefault) {
  // A facet at 70 degrees over the grid: left alone at a 60 degree limit, cut back to where it
  // rises above the tolerance at the default 80.
  MergedMesh at60 = slanted_piece(70);
  const mosaic_detail::ClipStats none = mosaic_detail::clip_overlaps(at60, {.tolerance = 0.1, .max_angle_deg = 60});
  EXPECT_EQ(none.triangles_cut + none.triangles_removed, 0u);
  MergedMesh m = slanted_piece(70);
  const mosaic_detail::ClipStats s = mosaic_detail::clip_overlaps(m, {.tolerance = 0.1});
  EXPECT_GT(s.triangles_cut, 0u);
  const double cut_at = 0.08 / std::sin(70 * std::numbers::pi / 180.0);
  EXPECT_NEAR(area_of(m, 0), (0.4 - cut_at) * 0.4, 2e-4);
  EXPECT_NEAR(area_of(m, 1), 1.0, 1e-6);
}

TEST(Clip, CutsASlantedPieceBackToTheToleranceAndLeavesSteeperOnesAlone) {
  MergedMesh steep = slanted_piece();
  const mosaic_detail::ClipStats none = mosaic_detail::clip_overlaps(steep, {.tolerance = 0.1, .max_angle_deg = 30});
  EXPECT_EQ(none.triangles_cut + none.triangles_removed, 0u);  // 45 degrees is beyond 30
  MergedMesh m = slanted_piece();
  const mosaic_detail::ClipStats s = mosaic_detail::clip_overlaps(m, {.tolerance = 0.1});
  EXPECT_EQ(s.triangles_removed, 8u);  // the first row of cells: both ends within 10 cm
  EXPECT_GT(s.triangles_cut, 0u);
  // Ground truth: the part of the slope higher than the tolerance, from s = 0.08 / sin 45.
  const double cut_at = 0.08 / std::sqrt(0.5);
  EXPECT_NEAR(area_of(m, 0), (0.4 - cut_at) * 0.4, 2e-4);
  EXPECT_NEAR(area_of(m, 1), 1.0, 1e-6);
  for (std::size_t t = 0; t < m.mesh.triangle_count(); ++t) {
    if (m.source_acq[t] != 0) continue;
    for (const std::uint32_t v : m.mesh.triangles[t]) EXPECT_GE(m.mesh.positions[v].z, 0.1f - 1e-3f);
  }
  EXPECT_EQ(non_manifold_edges(m.mesh), 0u);
}

TEST(Stitch, ClippingClosesASeamRunningOverAnotherPiece) {
  // Without clipping, the smaller piece's side lying over the larger one stays open; with it,
  // the pieces meet along x = 1 and the zipper joins them: only the union's outline is left.
  MergedMesh plain = overlapping_pieces(), clipped = overlapping_pieces();
  const StitchStats p = stitch(plain, {.snap = 0.1, .reach = 0.2, .weld = 0.005});
  const StitchStats c = stitch(clipped, {.snap = 0.1, .reach = 0.2, .weld = 0.005, .clip = 0.1});
  EXPECT_EQ(p.triangles_clipped + p.triangles_uncovered, 0u);
  EXPECT_GT(c.triangles_clipped, 0u);
  EXPECT_GT(p.open_boundary_after, 5.9);      // 4 + 2 x (0.6 + 0.4)
  EXPECT_LT(c.open_boundary_after, 4.9 + 0.05);  // 4 - 0.4 + 0.45 + 0.4 + 0.45
  EXPECT_NEAR(c.open_boundary_before, p.open_boundary_before, 1e-9);
  EXPECT_EQ(c.open_boundary_after, open_boundary_length(clipped.mesh));
  EXPECT_EQ(non_manifold_edges(clipped.mesh), 0u);
  EXPECT_EQ(repeated_directed_edges(clipped.mesh), 0u);
}

/// One welded 1 m x 1 m grid (0.1 m cells, normals +z): the rows below y = 0.5 from source
/// 0, above from source 1; the cells in `holes` (i, j) left out.
MergedMesh two_source_grid(const std::vector<std::pair<int, int>>& holes) {
  MergedMesh m;
  constexpr int n = 10;
  for (int j = 0; j <= n; ++j) {
    for (int i = 0; i <= n; ++i) m.mesh.positions.push_back({0.1f * float(i), 0.1f * float(j), 0});
  }
  const auto id = [&](int i, int j) { return static_cast<std::uint32_t>(j * (n + 1) + i); };
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      if (std::find(holes.begin(), holes.end(), std::pair{i, j}) != holes.end()) continue;
      for (const Triangle& t : {Triangle{id(i, j), id(i + 1, j), id(i + 1, j + 1)}, Triangle{id(i, j), id(i + 1, j + 1), id(i, j + 1)}}) {
        m.mesh.triangles.push_back(t);
        m.mesh.triangle_ids.push_back({});
        m.source_acq.push_back(j < n / 2 ? 0 : 1);
        m.source_triangle.push_back(static_cast<std::int32_t>(m.source_triangle.size()));
      }
    }
  }
  return m;
}

mosaic_detail::GapFillStats fill_gaps(MergedMesh& m) {
  mosaic_detail::MeshTopology topo(m);
  return mosaic_detail::fill_seam_gaps(topo, {.max_width = 0.1, .max_perimeter = 2.0});
}

TEST(GapFill, ClosesASmallHoleBetweenTwoSources) {
  // The cell under the seam is missing: three of its sides are source 0's, one source 1's.
  MergedMesh m = two_source_grid({{4, 4}});
  const std::size_t before = m.mesh.triangle_count();
  const mosaic_detail::GapFillStats s = fill_gaps(m);
  EXPECT_EQ(s.gaps_filled, 1u);
  EXPECT_EQ(s.triangles_added, 2u);
  ASSERT_EQ(m.mesh.triangle_count(), before + 2);
  EXPECT_NEAR(open_boundary_length(m.mesh), 4.0, 1e-6);  // only the outline is left
  EXPECT_EQ(repeated_directed_edges(m.mesh), 0u);
  EXPECT_EQ(non_manifold_edges(m.mesh), 0u);
  double added_area = 0;
  for (std::size_t t = before; t < m.mesh.triangle_count(); ++t) {
    EXPECT_EQ(m.source_acq[t], kNoSource);
    EXPECT_EQ(m.source_triangle[t], kNoSource);
    const TriangleCorners c = m.mesh.corners(t);
    const Vec3d n = cross(c[1] - c[0], c[2] - c[0]);
    EXPECT_GT(n.z, 0) << "a fill triangle faces away from its neighbours";
    added_area += 0.5 * norm(n);
  }
  EXPECT_NEAR(added_area, 0.01, 1e-6);
}

TEST(GapFill, LeavesHolesOfOneSourceAndWideHolesOpen) {
  MergedMesh one_source = two_source_grid({{4, 2}});  // inside source 0: a hole of that scan
  EXPECT_EQ(fill_gaps(one_source).gaps_filled, 0u);
  // Across the seam, 0.3 m x 0.2 m: 12 cm wide (twice the area over the perimeter).
  MergedMesh wide = two_source_grid({{3, 4}, {4, 4}, {5, 4}, {3, 5}, {4, 5}, {5, 5}});
  const std::size_t before = wide.mesh.triangle_count();
  EXPECT_EQ(fill_gaps(wide).gaps_filled, 0u);
  EXPECT_EQ(wide.mesh.triangle_count(), before);
  MergedMesh narrow = two_source_grid({{3, 4}, {4, 4}, {5, 4}, {6, 4}});  // 0.4 m x 0.1 m: 8 cm
  const mosaic_detail::GapFillStats s = fill_gaps(narrow);
  EXPECT_EQ(s.gaps_filled, 1u);
  EXPECT_EQ(s.triangles_added, 8u);  // a polygon of 10 vertices (4 + 1 + 4 + 1), 8 triangles
  EXPECT_NEAR(open_boundary_length(narrow.mesh), 4.0, 1e-6);
  EXPECT_EQ(repeated_directed_edges(narrow.mesh), 0u);
}

TEST(GapFill, ClosesANonConvexGapWithoutFoldingIt) {
  // An L-shaped gap: ear clipping must not take the reflex corner's diagonal, which would
  // cover the cell that is still there.
  MergedMesh m = two_source_grid({{4, 4}, {5, 4}, {5, 5}});
  const std::size_t before = m.mesh.triangle_count();
  const mosaic_detail::GapFillStats s = fill_gaps(m);
  ASSERT_EQ(s.gaps_filled, 1u);
  double added_area = 0;
  for (std::size_t t = before; t < m.mesh.triangle_count(); ++t) {
    const TriangleCorners c = m.mesh.corners(t);
    added_area += 0.5 * norm(cross(c[1] - c[0], c[2] - c[0]));
  }
  EXPECT_NEAR(added_area, 0.03, 1e-6);  // exactly the three cells: nothing folded over
  EXPECT_NEAR(open_boundary_length(m.mesh), 4.0, 1e-6);
  EXPECT_EQ(repeated_directed_edges(m.mesh), 0u);
}

TEST(GapFill, ClosesTwoGapsMeetingAtAPinchedVertex) {
  // Two missing cells touching at one corner, (0.4, 0.5) on the seam: that vertex starts two
  // boundary edges, and each loop must follow its own hole through it.
  MergedMesh m = two_source_grid({{3, 4}, {4, 5}});
  const std::size_t before = m.mesh.triangle_count();
  const mosaic_detail::GapFillStats s = fill_gaps(m);
  EXPECT_EQ(s.gaps_filled, 2u);
  EXPECT_NEAR(open_boundary_length(m.mesh), 4.0, 1e-6);
  EXPECT_EQ(repeated_directed_edges(m.mesh), 0u);
  double added_area = 0;
  for (std::size_t t = before; t < m.mesh.triangle_count(); ++t) {
    const TriangleCorners c = m.mesh.corners(t);
    const Vec3d n = cross(c[1] - c[0], c[2] - c[0]);
    EXPECT_GT(n.z, 0) << "a fill triangle faces away from its neighbours";
    added_area += 0.5 * norm(n);
  }
  EXPECT_NEAR(added_area, 0.02, 1e-6);  // the two cells, nothing across the pinch
}

/// Source 0 above y = 0, source 1 below, joined along the seam except between a and b,
/// where source 1's boundary bends 1 cm up into source 0 through x: the loop a -> b -> x
/// winds the wrong way (two layers, not a hole), so a fill would face down.
MergedMesh overlap_sliver() {
  MergedMesh m;
  m.mesh.positions = {{-0.5f, 0, 0},   {0, 0, 0},     {0.5f, 0, 0},  {1, 0, 0},  // p0 a b p3
                      {0.25f, 0.01f, 0},                                     // x
                      {-0.25f, 0.5f, 0}, {0.25f, 0.5f, 0}, {0.75f, 0.5f, 0},  // c0 c1 c2
                      {-0.25f, -0.5f, 0}, {0.25f, -0.5f, 0}, {0.75f, -0.5f, 0}};  // d0 d1 d2
  add_triangles(m, 0, {{0, 1, 5}, {1, 2, 6}, {2, 3, 7}, {1, 6, 5}, {2, 7, 6}});
  add_triangles(m, 1, {{1, 0, 8}, {2, 4, 9}, {4, 1, 9}, {3, 2, 10}, {1, 8, 9}, {2, 9, 10}});
  return m;
}

TEST(GapFill, ClosesAnOverlapSliverBySplittingItsLongEdge) {
  // Splitting source 0's edge a -> b at x closes the loop with every triangle still facing up.
  MergedMesh m = overlap_sliver();
  const double outline = open_boundary_length(m.mesh) - 0.5 - 2 * std::hypot(0.25, 0.01);
  const mosaic_detail::GapFillStats s = fill_gaps(m);
  EXPECT_EQ(s.gaps_filled, 0u);
  EXPECT_EQ(s.gaps_split, 1u);
  EXPECT_NEAR(open_boundary_length(m.mesh), outline, 1e-6);
  EXPECT_EQ(repeated_directed_edges(m.mesh), 0u);
  EXPECT_EQ(non_manifold_edges(m.mesh), 0u);
  EXPECT_EQ(m.mesh.triangle_count(), 12u);  // source 0's a -> b triangle became two
  for (std::size_t t = 0; t < m.mesh.triangle_count(); ++t) {
    const TriangleCorners c = m.mesh.corners(t);
    EXPECT_GT(cross(c[1] - c[0], c[2] - c[0]).z, 0) << "triangle " << t << " faces down";
  }
  EXPECT_EQ(std::count(m.source_acq.begin(), m.source_acq.end(), 0), 6);  // the split keeps provenance
}

TEST(GapFill, DoesNotSplitATriangleOfOutputStitchedBefore) {
  // The same loop with source 0 done (stitched part by part, StitchSurroundings): its
  // triangle a -> b stays as it is and the loop stays open.
  MergedMesh m = overlap_sliver();
  std::vector<std::uint8_t> roles(m.mesh.vertex_count(), static_cast<std::uint8_t>(VertexRole::free));
  for (std::size_t t = 0; t < m.mesh.triangle_count(); ++t) {
    if (m.source_acq[t] != 0) continue;
    for (const std::uint32_t v : m.mesh.triangles[t]) roles[v] = static_cast<std::uint8_t>(VertexRole::done);
  }
  mosaic_detail::MeshTopology topo(m, {.vertex_roles = roles});
  const mosaic_detail::GapFillStats s = mosaic_detail::fill_seam_gaps(topo, {.max_width = 0.1, .max_perimeter = 2.0});
  EXPECT_EQ(s.gaps_split + s.gaps_filled, 0u);
  EXPECT_EQ(s.gaps_refused, 1u);
  EXPECT_EQ(m.mesh.triangle_count(), 11u);
  EXPECT_EQ(m.mesh.triangles[1], (Triangle{1, 2, 6}));
}

/// Source 0 (above y = 0) ends in a sliver cut triangle a -> b -> s, its apex s 5 mm above
/// the edge; source 1 (below) reaches 1 cm above the edge at x, past the apex, as where two
/// clipped boundaries zigzag across each other.
MergedMesh sliver_and_crossing_vertex() {
  MergedMesh m;
  m.mesh.positions = {{0, 0, 0},     {0.5f, 0, 0},    {0.25f, 0.005f, 0}, {0, 0.5f, 0}, {0.5f, 0.5f, 0},  // a b s c0 c1
                      {0, 0, 0},     {0.25f, 0.01f, 0}, {0.5f, 0, 0},                                     // a1 x b1
                      {0, -0.5f, 0}, {0.5f, -0.5f, 0}};                                                  // d0 d1
  add_triangles(m, 0, {{0, 1, 2}, {0, 2, 3}, {2, 1, 4}, {2, 4, 3}});
  add_triangles(m, 1, {{5, 8, 6}, {8, 9, 6}, {6, 9, 7}});
  return m;
}

TEST(Snap, MovesAVertexOntoTheEdgeWhenSplittingAroundItWouldFlipASliver) {
  MergedMesh plain = sliver_and_crossing_vertex();
  mosaic_detail::MeshTopology plain_topo(plain);
  EXPECT_FALSE(mosaic_detail::split_boundary_edge(plain_topo, 0, 1, {6}));  // (a, x, s) would face down

  MergedMesh m = sliver_and_crossing_vertex();
  mosaic_detail::MeshTopology topo(m);
  const mosaic_detail::SnapStats s = mosaic_detail::snap_boundaries(topo, 0.05);
  EXPECT_EQ(s.vertices_merged, 2u);  // a and b with their twins
  EXPECT_EQ(s.edges_split, 1u);
  EXPECT_EQ(m.mesh.positions[6], (Vec3f{0.25f, 0, 0}));  // x moved onto a -> b
  EXPECT_NEAR(open_boundary_length(m.mesh), 3.0, 1e-6);  // only the outline of the union
  EXPECT_EQ(repeated_directed_edges(m.mesh), 0u);
  for (std::size_t t = 0; t < m.mesh.triangle_count(); ++t) {
    const TriangleCorners c = m.mesh.corners(t);
    EXPECT_GT(cross(c[1] - c[0], c[2] - c[0]).z, 0) << "triangle " << t << " faces down";
  }
}

TEST(Snap, LeavesAVertexWhereMovingItOntoTheEdgeWouldFlipItsOwnTriangle) {
  MergedMesh m = sliver_and_crossing_vertex();
  m.mesh.positions[8] = {0.24f, 0.005f, 0};  // d0 just beside x, below its line: moving x down flips (d0, d1, x)
  m.mesh.positions[9] = {0.5f, -0.5f, 0};
  mosaic_detail::MeshTopology topo(m);
  const Vec3f x = m.mesh.positions[6];
  EXPECT_FALSE(mosaic_detail::split_boundary_edge_onto(topo, 0, 1, {6}, 0.05));
  EXPECT_EQ(m.mesh.positions[6], x);  // the move is undone
  EXPECT_EQ(m.mesh.triangle_count(), 7u);
}

}  // namespace
}  // namespace citymesh
