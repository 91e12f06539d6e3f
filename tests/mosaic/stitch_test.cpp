// SPDX-License-Identifier: MIT
#include "citymesh/mosaic/stitch.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <random>

namespace citymesh {
namespace {

/// A flat grid of nx x ny cells of size `step` at x0, split into triangles, normals +z
/// (counter-clockwise seen from above), appended to `out` with source `source`.
void add_grid(MergedMesh& out, float x0, float y0, int nx, int ny, float step, std::int32_t source, float z = 0) {
  const auto base = static_cast<std::uint32_t>(out.mesh.positions.size());
  for (int j = 0; j <= ny; ++j) {
    for (int i = 0; i <= nx; ++i) out.mesh.positions.push_back({x0 + float(i) * step, y0 + float(j) * step, z});
  }
  const auto id = [&](int i, int j) { return base + static_cast<std::uint32_t>(j * (nx + 1) + i); };
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      for (const Triangle& t : {Triangle{id(i, j), id(i + 1, j), id(i + 1, j + 1)}, Triangle{id(i, j), id(i + 1, j + 1), id(i, j + 1)}}) {
        out.mesh.triangles.push_back(t);
        out.mesh.triangle_ids.push_back({});
        out.source_acq.push_back(source);
        out.source_triangle.push_back(static_cast<std::int32_t>(out.source_triangle.size()));
      }
    }
  }
}

/// Edges used by more than two triangles.
std::size_t non_manifold_edges(const Mesh& m) {
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> uses;
  for (const Triangle& t : m.triangles) {
    for (int k = 0; k < 3; ++k) ++uses[{std::min(t[k], t[(k + 1) % 3]), std::max(t[k], t[(k + 1) % 3])}];
  }
  return static_cast<std::size_t>(std::count_if(uses.begin(), uses.end(), [](const auto& u) { return u.second > 2; }));
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

/// Directed edges used by more than one triangle (a fold, or an orientation flip).
std::size_t repeated_directed_edges(const Mesh& m) {
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> uses;
  for (const Triangle& t : m.triangles) {
    for (int k = 0; k < 3; ++k) ++uses[{t[k], t[(k + 1) % 3]}];
  }
  return static_cast<std::size_t>(std::count_if(uses.begin(), uses.end(), [](const auto& u) { return u.second > 1; }));
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

}  // namespace
}  // namespace citymesh
