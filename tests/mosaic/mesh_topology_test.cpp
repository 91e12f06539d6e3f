// SPDX-License-Identifier: MIT
// The stitching's vertex-to-triangle incidence against brute force over every triangle.
#include "mesh_topology.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <random>

#include "citymesh/mosaic/edges.h"

namespace citymesh {
namespace {

using mosaic_detail::MeshTopology;

/// Random triangles over few vertices: shared edges, edges used twice the same way, three
/// times, and degenerate triangles all occur.
MergedMesh random_mesh(std::mt19937& rng, std::uint32_t vertices, std::size_t triangles) {
  MergedMesh m;
  m.mesh.positions.assign(vertices, Vec3f{0, 0, 0});
  const auto vertex = [&] { return static_cast<std::uint32_t>(rng() % vertices); };
  for (std::size_t t = 0; t < triangles; ++t) {
    Triangle tri{vertex(), vertex(), vertex()};
    if (rng() % 8 != 0) {
      while (tri[1] == tri[0]) tri[1] = vertex();
      while (tri[2] == tri[0] || tri[2] == tri[1]) tri[2] = vertex();
    }
    m.mesh.triangles.push_back(tri);
    m.source_acq.push_back(static_cast<std::int32_t>(rng() % 3));
    m.source_triangle.push_back(static_cast<std::int32_t>(t));
  }
  return m;
}

bool uses(const Triangle& tri, std::uint32_t from, std::uint32_t to) {
  for (int k = 0; k < 3; ++k) {
    if (tri[k] == from && tri[(k + 1) % 3] == to) return true;
  }
  return false;
}

bool brute_has(const MergedMesh& m, std::uint32_t from, std::uint32_t to) {
  return std::any_of(m.mesh.triangles.begin(), m.mesh.triangles.end(), [&](const Triangle& tri) { return uses(tri, from, to); });
}

/// The directed edges whose reverse no triangle runs, in triangle and corner order.
std::vector<std::array<std::uint32_t, 3>> brute_half_edges(const MergedMesh& m) {
  std::vector<std::array<std::uint32_t, 3>> out;
  for (std::uint32_t t = 0; t < m.mesh.triangle_count(); ++t) {
    const Triangle& tri = m.mesh.triangles[t];
    for (int k = 0; k < 3; ++k) {
      if (!brute_has(m, tri[(k + 1) % 3], tri[k])) out.push_back({tri[k], tri[(k + 1) % 3], t});
    }
  }
  return out;
}

void expect_matches_brute_force(const MergedMesh& m, const MeshTopology& topo, std::uint32_t vertices) {
  EXPECT_EQ(topo.boundary_edges(), boundary_edges(m.mesh.triangles));
  std::vector<std::array<std::uint32_t, 3>> half;
  for (const mosaic_detail::DirectedEdge& e : topo.boundary_half_edges()) half.push_back({e.from, e.to, e.triangle});
  EXPECT_EQ(half, brute_half_edges(m));
  for (std::uint32_t a = 0; a < vertices; ++a) {
    for (std::uint32_t b = 0; b < vertices; ++b) {
      const std::optional<std::uint32_t> t = topo.triangle_with(a, b);
      ASSERT_EQ(t.has_value(), brute_has(m, a, b)) << a << " -> " << b;
      if (t) {
        EXPECT_TRUE(uses(m.mesh.triangles[*t], a, b)) << a << " -> " << b;
      }
    }
  }
}

TEST(MeshTopology, EdgesAndBoundaryEqualBruteForceAsTrianglesChange) {
  std::mt19937 rng(5);
  for (int trial = 0; trial < 400; ++trial) {
    const std::uint32_t vertices = 4 + static_cast<std::uint32_t>(rng() % 12);
    MergedMesh m = random_mesh(rng, vertices, 1 + rng() % 24);
    MeshTopology topo(m);
    expect_matches_brute_force(m, topo, vertices);
    // Rename a vertex in one triangle, as a merge does, and add a triangle, as a strip does.
    const auto t = static_cast<std::uint32_t>(rng() % m.mesh.triangle_count());
    Triangle& tri = m.mesh.triangles[t];
    const auto now = static_cast<std::uint32_t>(rng() % vertices);
    if (tri[0] != tri[1] && tri[1] != tri[2] && tri[0] != tri[2] && now != tri[1] && now != tri[2] && now != tri[0]) {
      std::erase(topo.edit(tri[0]), t);
      topo.edit(now).push_back(t);
      tri[0] = now;
    }
    m.mesh.triangles.push_back({0, 1, 2});
    m.source_acq.push_back(kNoSource);
    m.source_triangle.push_back(kNoSource);
    topo.add_triangle(static_cast<std::uint32_t>(m.mesh.triangle_count() - 1));
    expect_matches_brute_force(m, topo, vertices);
  }
}

TEST(MeshTopology, EdgesFreeIgnoresTheTrianglesReplacedAndRefusesRepeats) {
  MergedMesh m;
  m.mesh.positions.assign(5, Vec3f{0, 0, 0});
  m.mesh.triangles = {{0, 1, 2}, {0, 2, 3}};
  m.source_acq = {0, 0};
  m.source_triangle = {0, 1};
  const MeshTopology topo(m);
  const std::vector<Triangle> uses_0_1{{0, 1, 4}};
  EXPECT_FALSE(topo.edges_free(uses_0_1, {}));
  const std::uint32_t first = 0;
  EXPECT_TRUE(topo.edges_free(uses_0_1, std::span(&first, 1)));
  const std::vector<std::uint32_t> both{0, 1};
  const std::vector<Triangle> twice{{1, 3, 0}, {3, 0, 1}};  // 3 -> 0 in both
  EXPECT_FALSE(topo.edges_free(twice, both));
  const std::vector<Triangle> once{{1, 3, 0}};
  EXPECT_TRUE(topo.edges_free(once, both));
  EXPECT_EQ(topo.piece_of_vertex(3), 0);
}

}  // namespace
}  // namespace citymesh
