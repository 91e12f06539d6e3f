// SPDX-License-Identifier: MIT
// The vertex-to-triangle incidence of a merged mesh, kept up to date while stitching changes
// it (internal to stitching). Directed edges are found by looking at the few triangles around
// a vertex: no hash table of every edge of a city-sized mesh (18 M entries, a gigabyte, and
// most of the stitching time).
#pragma once

#include <cstdint>
#include <deque>
#include <optional>
#include <span>
#include <vector>

#include "citymesh/mosaic/edges.h"
#include "citymesh/mosaic/merged_mesh.h"
#include "citymesh/mosaic/stitch.h"

namespace citymesh::mosaic_detail {

/// A directed edge from -> to, as `triangle` runs it.
struct DirectedEdge {
  std::uint32_t from, to, triangle;
};

class MeshTopology {
 public:
  /// `around`: the vertices' roles and where the part's own triangles start (its source sizes
  /// are not read); the caller keeps its arrays alive. `own_pieces_apart`: the pieces of one
  /// source (source_pieces()) count as different sides of a seam, as two sources do.
  explicit MeshTopology(MergedMesh& merged, const StitchSurroundings& around = {}, bool own_pieces_apart = false);

  [[nodiscard]] MergedMesh& merged() const { return merged_; }
  [[nodiscard]] const Triangle& triangle(std::uint32_t t) const { return merged_.mesh.triangles[t]; }
  [[nodiscard]] Vec3d position(std::uint32_t v) const { return Vec3d(merged_.mesh.positions[v]); }
  /// Twice the area times the unit normal of the triangle (a, b, c) of this mesh's vertices.
  [[nodiscard]] Vec3d winding(const Triangle& t) const {
    const Vec3d a = position(t[0]);
    return cross(position(t[1]) - a, position(t[2]) - a);
  }

  /// Whether v must stay where and what it is (a vertex of a part stitched before or after).
  [[nodiscard]] bool frozen(std::uint32_t v) const { return role_of(around_.vertex_roles, v) != VertexRole::free; }
  /// Whether seams may be joined to v: not a held vertex, nor one of a part stitched
  /// afterwards unless this part's triangles use it too (it lies on the border between the
  /// two): a triangle with a free corner, or any of the part's own when they are told.
  [[nodiscard]] bool joinable(std::uint32_t v) const;
  /// Whether triangle t must stay as it is: its three corners are frozen. (A free triangle
  /// whose corners all happen to be frozen is kept as it is too: nothing it could become
  /// would leave them in place anyway but a split of its edges.)
  [[nodiscard]] bool frozen_triangle(std::uint32_t t) const {
    return all_corners_frozen(triangle(t), around_.vertex_roles);
  }

  /// The triangles using vertex v, in the order they were added.
  [[nodiscard]] std::span<const std::uint32_t> triangles_of(std::uint32_t v) const;
  /// v's list, to change (copied out of the packed lists on its first change).
  std::vector<std::uint32_t>& edit(std::uint32_t v);
  /// Registers triangle t (already in the mesh) with its vertices; `piece`: its side of the
  /// seams (that of the triangle it was split from; kNoSource for a stitch triangle).
  void add_triangle(std::uint32_t t, std::int32_t piece = kNoSource);
  /// Which side of a seam triangle t is on: its source, or with own pieces apart its piece
  /// (source_pieces()); kNoSource for a stitch triangle.
  [[nodiscard]] std::int32_t piece(std::uint32_t t) const {
    return own_pieces_apart() ? pieces_[t] : merged_.source_acq[t];
  }
  /// Whether the pieces of one source are different sides of a seam (else each source is one).
  [[nodiscard]] bool own_pieces_apart() const { return own_pieces_apart_; }

  /// The triangle using the directed edge from -> to (the first one if several do).
  [[nodiscard]] std::optional<std::uint32_t> triangle_with(std::uint32_t from, std::uint32_t to) const;
  [[nodiscard]] bool has(std::uint32_t from, std::uint32_t to) const { return triangle_with(from, to).has_value(); }
  /// True when no directed edge of `tris` is used by a triangle other than those in
  /// `replaced` (about to be overwritten by `tris`), nor twice among `tris`.
  [[nodiscard]] bool edges_free(std::span<const Triangle> tris, std::span<const std::uint32_t> replaced) const;
  /// The source of the first triangle around v, kNoSource for none.
  [[nodiscard]] std::int32_t source_of_vertex(std::uint32_t v) const;
  /// The piece of the first triangle around v, kNoSource for none.
  [[nodiscard]] std::int32_t piece_of_vertex(std::uint32_t v) const;

  /// The edges used by exactly one triangle, sorted as boundary_edges() sorts them (which
  /// gives the same list, from the lists around each vertex instead of a sort of every edge).
  [[nodiscard]] std::vector<EdgeUse> boundary_edges() const;
  /// Total length of boundary_edges() (open_boundary_length() without sorting every edge).
  [[nodiscard]] double boundary_length() const;
  /// The directed edges whose reverse no triangle uses, oriented as their triangle runs
  /// them, in triangle order: the boundary that snapping walks and gap closing follows.
  [[nodiscard]] std::vector<DirectedEdge> boundary_half_edges() const;

 private:
  MergedMesh& merged_;
  StitchSurroundings around_;
  bool own_pieces_apart_;
  std::vector<std::int32_t> pieces_;             ///< per triangle: piece() (empty unless own pieces apart)
  std::vector<std::uint32_t> offsets_, packed_;  ///< the lists of the mesh as given, compressed rows
  std::vector<std::uint32_t> edited_;            ///< per vertex: its list in `edits_`, or UINT32_MAX
  std::deque<std::vector<std::uint32_t>> edits_;  ///< a deque: references stay valid as it grows
};

}  // namespace citymesh::mosaic_detail
