// SPDX-License-Identifier: MIT
// Pieces of one source that share no vertex (a spinning scanner's turns, meshed one by one):
// found as the components of each source, and stitched, clipped and gap-closed as pieces of
// different sources are.
#include <gtest/gtest.h>

#include <algorithm>
#include <queue>
#include <random>
#include <set>
#include <utility>

#include "citymesh/mosaic/merged_mesh.h"
#include "citymesh/mosaic/stitch.h"
#include "clip.h"
#include "gap_fill.h"
#include "mesh_topology.h"
#include "stitch_fixtures.h"

namespace citymesh {
namespace {

using test::add_grid;
using test::non_manifold_edges;
using test::repeated_directed_edges;

/// Brute force: per triangle, the smallest index of the triangles reached from it through
/// shared vertices without leaving its source.
std::vector<std::int32_t> pieces_by_search(const MergedMesh& m) {
  const std::size_t n = m.mesh.triangle_count();
  std::vector<std::int32_t> piece(n, kNoSource);
  const auto share_a_vertex = [&](std::size_t a, std::size_t b) {
    for (const std::uint32_t u : m.mesh.triangles[a]) {
      for (const std::uint32_t v : m.mesh.triangles[b]) {
        if (u == v) return true;
      }
    }
    return false;
  };
  for (std::size_t start = 0; start < n; ++start) {
    if (m.source_acq[start] < 0 || piece[start] != kNoSource) continue;
    // Triangles are visited in index order, so `start` is the smallest of its piece.
    std::queue<std::size_t> open;
    open.push(start);
    piece[start] = static_cast<std::int32_t>(start);
    while (!open.empty()) {
      const std::size_t t = open.front();
      open.pop();
      for (std::size_t u = 0; u < n; ++u) {
        if (piece[u] == kNoSource && m.source_acq[u] == m.source_acq[t] && share_a_vertex(t, u)) {
          piece[u] = static_cast<std::int32_t>(start);
          open.push(u);
        }
      }
    }
  }
  return piece;
}

TEST(SourcePieces, AreTheComponentsOfEachSourceThroughSharedVerticesNamedByTheirFirstTriangle) {
  std::mt19937 rng(7);
  for (int round = 0; round < 40; ++round) {
    // Few vertices, many sources and stitch triangles: vertices shared by several sources,
    // and pieces joined only through another source's triangles, are common.
    const auto vertices = static_cast<std::uint32_t>(8 + rng() % 40);
    const std::size_t triangles = 1 + rng() % 60;
    const int sources = 1 + static_cast<int>(rng() % 4);
    MergedMesh m;
    m.mesh.positions.assign(vertices, Vec3f{});
    for (std::size_t t = 0; t < triangles; ++t) {
      m.mesh.triangles.push_back({static_cast<std::uint32_t>(rng() % vertices),
                                  static_cast<std::uint32_t>(rng() % vertices),
                                  static_cast<std::uint32_t>(rng() % vertices)});
      m.source_acq.push_back(static_cast<std::int32_t>(rng() % static_cast<unsigned>(sources + 1)) - 1);  // -1: stitch
      m.source_triangle.push_back(static_cast<std::int32_t>(t));
    }
    EXPECT_EQ(source_pieces(m), pieces_by_search(m)) << "round " << round;
  }
}

TEST(Stitch, JoinsTwoPiecesOfOneSourceThatShareNoVertex) {
  // Two turns of one pass side by side, 6 cm apart: as two sources would be, they are zipped.
  MergedMesh m;
  add_grid(m, 0, 0, 10, 10, 0.1f, 0);
  add_grid(m, 1.06f, 0.013f, 8, 9, 0.11f, 0, 0.01f);
  ASSERT_EQ(source_pieces(m).back(), 200);  // the second grid is a piece of its own
  MergedMesh apart = m;
  const double before = open_boundary_length(m.mesh);
  const StitchStats s = stitch(m, {.snap = 0.02, .reach = 0.2, .weld = 0.005, .join_own_pieces = true});
  EXPECT_GE(s.strips, 1u);
  EXPECT_GT(s.triangles_added, 15u);
  EXPECT_LT(s.open_boundary_after, before - 1.7);  // the two facing sides, about 1 m each
  EXPECT_EQ(s.open_boundary_after, open_boundary_length(m.mesh));
  EXPECT_EQ(non_manifold_edges(m.mesh), 0u);
  EXPECT_EQ(repeated_directed_edges(m.mesh), 0u);
  for (std::size_t t = 0; t < m.mesh.triangle_count(); ++t) {
    const TriangleCorners c = m.mesh.corners(t);
    EXPECT_GT(cross(c[1] - c[0], c[2] - c[0]).z, 0) << "triangle " << t << " is flipped or flat";
  }
  // Not told to (the default), the same pieces stay as they are.
  const StitchStats off = stitch(apart, {.snap = 0.02, .reach = 0.2, .weld = 0.005});
  EXPECT_EQ(off.triangles_added, 0u);
  EXPECT_NEAR(off.open_boundary_after, before, 1e-9);
}

using TriangleRange = std::pair<std::int32_t, std::int32_t>;  ///< source triangles [first, second)

/// The vertices of the triangles whose source triangle lies in `range`.
std::set<std::uint32_t> vertices_of(const MergedMesh& m, TriangleRange range) {
  std::set<std::uint32_t> out;
  for (std::size_t t = 0; t < m.mesh.triangle_count(); ++t) {
    if (m.source_triangle[t] >= range.first && m.source_triangle[t] < range.second) {
      out.insert(m.mesh.triangles[t].begin(), m.mesh.triangles[t].end());
    }
  }
  return out;
}

/// Vertices used by triangles of both ranges.
std::size_t shared_vertices(const MergedMesh& m, TriangleRange a, TriangleRange b) {
  const std::set<std::uint32_t> of_a = vertices_of(m, a), of_b = vertices_of(m, b);
  return static_cast<std::size_t>(
      std::count_if(of_a.begin(), of_a.end(), [&](std::uint32_t v) { return of_b.contains(v); }));
}

/// Whether the triangles of ranges `a` and `b` are joined after stitching: they share a
/// vertex, or a stitch triangle uses a vertex of each.
bool joined(const MergedMesh& m, TriangleRange a, TriangleRange b) {
  if (shared_vertices(m, a, b) > 0) return true;
  const std::set<std::uint32_t> of_a = vertices_of(m, a), of_b = vertices_of(m, b);
  for (std::size_t t = 0; t < m.mesh.triangle_count(); ++t) {
    if (m.source_acq[t] != kNoSource) continue;
    const Triangle& tri = m.mesh.triangles[t];
    const auto uses = [&](const std::set<std::uint32_t>& of) {
      return std::any_of(tri.begin(), tri.end(), [&](std::uint32_t v) { return of.contains(v); });
    };
    if (uses(of_a) && uses(of_b)) return true;
  }
  return false;
}

TEST(Stitch, ZipsATurnToAnotherSourceBeforeANearerTurnOfItsOwnPass) {
  // Turn A (source 0, 1 m x 1 m); source C 10 cm beyond A's side x = 1 (source triangles
  // 200..343); turn B (344..443) lying 4 cm over C, its side 5.7 cm from A's (4 cm beyond, 4
  // cm up). The nearest is A's own pass's other turn, but a seam between passes comes first.
  const StitchParams params{.snap = 0.01, .reach = 0.2, .weld = 0.005, .join_own_pieces = true};
  const auto scene = [](std::int32_t b_source) {
    MergedMesh m;
    add_grid(m, 0, 0, 10, 10, 0.1f, 0);
    add_grid(m, 1.1f, 0, 8, 9, 0.11f, 1);
    add_grid(m, 1.04f, 0, 5, 10, 0.1f, b_source, 0.04f);
    return m;
  };
  constexpr TriangleRange a{0, 200}, c{200, 344}, b{344, 444};
  MergedMesh own = scene(0);
  const StitchStats s = stitch(own, params);
  EXPECT_GE(s.strips, 1u);
  EXPECT_TRUE(joined(own, a, c));
  EXPECT_FALSE(joined(own, a, b));
  // Control: when B is a third source, the nearer one (B) is the partner.
  MergedMesh other = scene(2);
  stitch(other, params);
  EXPECT_TRUE(joined(other, a, b));
  EXPECT_FALSE(joined(other, a, c));
}

TEST(Stitch, SnapsATurnToAnotherSourceBeforeANearerTurnOfItsOwnPass) {
  // Turn A (source 0, 1 m x 1 m); source C 1.9 cm beyond A's side x = 1 (source triangles
  // 200..359); turn B (source triangles 360..419) over A's strip y in [0.2, 0.8], its side
  // 1.5 cm from A's (1.2 cm in, 0.9 cm up). B is nearer, C within the snap tolerance too:
  // the 11 vertices of A's side become C's. B's side is then 2.3 cm from them: left alone.
  const StitchParams params{.snap = 0.02, .reach = 0.02, .weld = 0.001, .join_own_pieces = true};
  const auto scene = [](std::int32_t b_source) {
    MergedMesh m;
    add_grid(m, 0, 0, 10, 10, 0.1f, 0);
    add_grid(m, 1.019f, 0, 8, 10, 0.1f, 1);
    add_grid(m, 0.488f, 0.2f, 5, 6, 0.1f, b_source, 0.009f);
    return m;
  };
  constexpr TriangleRange a{0, 200}, c{200, 360}, b{360, 420};
  MergedMesh own = scene(0);
  const StitchStats s = stitch(own, params);
  EXPECT_EQ(s.vertices_snapped, 11u);
  EXPECT_EQ(shared_vertices(own, a, c), 11u);
  EXPECT_EQ(shared_vertices(own, a, b), 0u);
  // Control: when B is a third source, the nearer one (B) is preferred. It takes every other
  // vertex of the 7 it faces (y = 0.2, 0.4, 0.6, 0.8: two neighbours merged would give A's and
  // B's sides, running the same way, one directed edge, a fold); C takes the other 7.
  MergedMesh other = scene(2);
  stitch(other, params);
  EXPECT_EQ(shared_vertices(other, a, b), 4u);
  EXPECT_EQ(shared_vertices(other, a, c), 7u);
}

/// Area of the triangles whose source triangle lies in [first, last).
double area_from(const MergedMesh& m, std::int32_t first, std::int32_t last) {
  double total = 0;
  for (std::size_t t = 0; t < m.mesh.triangle_count(); ++t) {
    if (m.source_triangle[t] < first || m.source_triangle[t] >= last) continue;
    const TriangleCorners c = m.mesh.corners(t);
    total += 0.5 * norm(cross(c[1] - c[0], c[2] - c[0]));
  }
  return total;
}

TEST(Clip, OfTwoOverlappingPiecesOfOneSourceTheLaterInItsFileYields) {
  // The earlier turn (source triangles 0..47, 0.6 m x 0.4 m from x = 0.85, 5 cm up) is the
  // smaller: the order in the file decides, not the size. The later turn (48..247, 1 m x 1 m)
  // reaches 15 cm under it: it is cut back to x = 0.85 there.
  MergedMesh m;
  add_grid(m, 0.85f, 0.2f, 6, 4, 0.1f, 0, 0.05f);
  add_grid(m, 0, 0, 10, 10, 0.1f, 0);
  MergedMesh apart = m;
  const mosaic_detail::ClipStats s = mosaic_detail::clip_overlaps(m, {.tolerance = 0.1, .own_tolerance = 0.1});
  EXPECT_GT(s.triangles_cut + s.triangles_removed, 0u);
  EXPECT_NEAR(area_from(m, 0, 48), 0.6 * 0.4, 1e-5);  // the earlier stays whole
  // Ground truth: the later grid less the rectangle [0.85, 1] x [0.2, 0.6] it lies under.
  // (A cut stays a tenth of an edge from its ends, so the cover's corners take a sliver more.)
  EXPECT_NEAR(area_from(m, 48, 248), 1.0 - 0.15 * 0.4, 4e-3);
  for (std::size_t t = 0; t < m.mesh.triangle_count(); ++t) {
    if (m.source_triangle[t] < 48) continue;
    const TriangleCorners c = m.mesh.corners(t);
    const Vec3d mid = (c[0] + c[1] + c[2]) / 3.0;
    EXPECT_FALSE(mid.x > 0.86 && mid.y > 0.21 && mid.y < 0.59)
        << "triangle " << t << " is still under the earlier turn";
  }
  EXPECT_EQ(non_manifold_edges(m.mesh), 0u);
  EXPECT_EQ(repeated_directed_edges(m.mesh), 0u);
  // 15 cm apart, within the clipping's tolerance but not within the one for its own: no cut.
  MergedMesh deeper;
  add_grid(deeper, 0.85f, 0.2f, 6, 4, 0.1f, 0, 0.15f);
  add_grid(deeper, 0, 0, 10, 10, 0.1f, 0);
  const mosaic_detail::ClipStats d = mosaic_detail::clip_overlaps(deeper, {.tolerance = 0.2, .own_tolerance = 0.1});
  EXPECT_EQ(d.triangles_cut + d.triangles_removed + d.vertices_added, 0u);
  // With no tolerance for its own (the default), one source never covers itself.
  const mosaic_detail::ClipStats off = mosaic_detail::clip_overlaps(apart, {.tolerance = 0.1});
  EXPECT_EQ(off.triangles_cut + off.triangles_removed + off.vertices_added, 0u);
}

/// Drops the triangles of `m` whose centroid lies in the cell [x, x + 0.1] x [y, y + 0.1].
void drop_cell(MergedMesh& m, float x, float y) {
  std::size_t kept = 0;
  for (std::size_t t = 0; t < m.mesh.triangle_count(); ++t) {
    const TriangleCorners c = m.mesh.corners(t);
    const Vec3d mid = (c[0] + c[1] + c[2]) / 3.0;
    if (mid.x > x && mid.x < x + 0.1 && mid.y > y && mid.y < y + 0.1) continue;
    m.mesh.triangles[kept] = m.mesh.triangles[t];
    m.mesh.triangle_ids[kept] = m.mesh.triangle_ids[t];
    m.source_acq[kept] = m.source_acq[t];
    m.source_triangle[kept] = m.source_triangle[t];
    ++kept;
  }
  m.mesh.triangles.resize(kept);
  m.mesh.triangle_ids.resize(kept);
  m.source_acq.resize(kept);
  m.source_triangle.resize(kept);
}

TEST(GapFill, ClosesAHoleBetweenTwoPiecesOfOneSourceButNotAHoleInsideOne) {
  // Two turns of one pass, one above the other along y = 0.5 (coincident boundaries, no
  // shared vertex); the earlier lacks a cell on that side: once snapped, a hole between them.
  const StitchParams params{.snap = 0.01, .reach = 0.01, .weld = 0.001, .gap = 0.1, .join_own_pieces = true};
  MergedMesh turns;
  add_grid(turns, 0, 0, 10, 5, 0.1f, 0);
  add_grid(turns, 0, 0.5f, 10, 5, 0.1f, 0);
  drop_cell(turns, 0.4f, 0.4f);
  MergedMesh apart = turns;
  const std::size_t before = turns.mesh.triangle_count();
  const StitchStats s = stitch(turns, params);
  EXPECT_EQ(s.gaps_filled, 1u);
  EXPECT_EQ(turns.mesh.triangle_count(), before + 2);
  EXPECT_NEAR(s.open_boundary_after, 4.0, 1e-4);  // only the outline is left
  EXPECT_EQ(repeated_directed_edges(turns.mesh), 0u);
  EXPECT_EQ(non_manifold_edges(turns.mesh), 0u);
  // Told not to join own pieces: neither snapped nor filled.
  StitchParams off = params;
  off.join_own_pieces = false;
  const StitchStats o = stitch(apart, off);
  EXPECT_EQ(o.vertices_snapped + o.gaps_filled + o.triangles_added, 0u);
  // A hole inside one piece is that scan's own: it stays open.
  MergedMesh holed;
  add_grid(holed, 0, 0, 10, 10, 0.1f, 0);
  drop_cell(holed, 0.4f, 0.4f);
  const StitchStats h = stitch(holed, params);
  EXPECT_EQ(h.gaps_filled + h.triangles_added, 0u);
  EXPECT_NEAR(h.open_boundary_after, 4.4, 1e-4);
}

TEST(Clip, ALaterTurnsTriangleSpanningAnEarlierTurnsHoleKeepsThePartOverTheHole) {
  // The earlier turn lacks the cells of [0.4, 0.6]^2; a later turn's single large triangle,
  // 2 cm under it, spans that hole with its corners over the earlier turn. Removed whole (its
  // corners are covered), it would open the hole; kept whole, it would double the earlier
  // turn around it. Split about its centroid and cut back along the spokes, what stays lies
  // over the hole.
  MergedMesh m;
  add_grid(m, 0, 0, 10, 10, 0.1f, 0);
  for (const float x : {0.4f, 0.5f}) {
    for (const float y : {0.4f, 0.5f}) drop_cell(m, x, y);
  }
  const std::size_t earlier = m.mesh.triangle_count();
  const auto base = static_cast<std::uint32_t>(m.mesh.positions.size());
  for (const Vec3f p : {Vec3f{0.2f, 0.25f, -0.02f}, Vec3f{0.85f, 0.3f, -0.02f}, Vec3f{0.45f, 0.85f, -0.02f}}) {
    m.mesh.positions.push_back(p);
  }
  m.mesh.triangles.push_back({base, base + 1, base + 2});
  m.mesh.triangle_ids.push_back({});
  m.source_acq.push_back(0);
  m.source_triangle.push_back(1000);  // later in the pass's file
  MergedMesh unsplit = m;
  MergedMesh stitched = m;
  const mosaic_detail::ClipStats s = mosaic_detail::clip_overlaps(m, {.tolerance = 0.2, .own_tolerance = 0.1});
  EXPECT_EQ(s.triangles_split, 1u);
  EXPECT_NEAR(area_from(m, 0, 1000), 1.0 - 0.04, 1e-5);  // the earlier turn stays whole
  const double kept = area_from(m, 1000, 1001);
  EXPECT_GT(kept, 0.01);  // at least a quarter of the hole's 0.04 m2
  EXPECT_LT(kept, 0.06);  // the triangle was 0.19 m2
  for (std::size_t t = earlier; t < m.mesh.triangle_count(); ++t) {
    const TriangleCorners c = m.mesh.corners(t);
    const Vec3d mid = (c[0] + c[1] + c[2]) / 3.0;
    EXPECT_TRUE(mid.x > 0.35 && mid.x < 0.65 && mid.y > 0.35 && mid.y < 0.65)
        << "part " << t << " lies beside the hole";
  }
  EXPECT_EQ(repeated_directed_edges(m.mesh), 0u);
  EXPECT_EQ(non_manifold_edges(m.mesh), 0u);
  // Without a tolerance for its own, nothing is split or cut.
  const mosaic_detail::ClipStats off = mosaic_detail::clip_overlaps(unsplit, {.tolerance = 0.2});
  EXPECT_EQ(off.triangles_split + off.triangles_removed + off.triangles_cut, 0u);
  // Stitching reports the split (the run's summary shows it).
  const StitchStats st = stitch(stitched, {.clip = 0.2, .join_own_pieces = true, .own_clip = 0.1});
  EXPECT_EQ(st.triangles_split, 1u);
}

}  // namespace
}  // namespace citymesh
