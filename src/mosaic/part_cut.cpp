// SPDX-License-Identifier: MIT
#include "part_cut.h"

#include <algorithm>

#include "citymesh/core/error.h"
#include "citymesh/core/key_union.h"

namespace citymesh::mosaic_detail {

namespace {

/// How strongly a role freezes a vertex: the strongest of a vertex's triangles wins.
int strength(VertexRole r) {
  switch (r) {
    case VertexRole::free: return 0;
    case VertexRole::later: return 1;
    case VertexRole::done: return 2;
    case VertexRole::held: return 3;
  }
  return 3;
}

/// What the cut knows of one vertex of the union.
struct VertexUse {
  std::uint32_t everywhere = 0;  ///< triangles of every loaded piece using it
  std::uint32_t in_cut = 0;      ///< of them, cut out
  VertexRole role = VertexRole::free;
  const KeyedPiece* piece = nullptr;  ///< a piece holding it, and its index there
  std::uint32_t index = 0;
};

void append_keyed_vertex(const KeyedPiece& p, std::uint32_t v, const Vec3d& origin, Mesh& m) {
  m.positions.push_back(to_local(p.positions[v], origin));
  if (!p.sensors.empty()) m.sensor_positions.push_back(to_local(p.sensors[v], origin));
  if (!p.times.empty()) m.times.push_back(p.times[v]);
  if (!p.intensities.empty()) m.intensities.push_back(p.intensities[v]);
  if (!p.colors.empty()) m.colors.push_back(p.colors[v]);
}

}  // namespace

PartCut cut_part(const KeyedPiece& own, std::span<const Neighbour> around, const Box3d& reach, const Vec3d& origin) {
  std::vector<const KeyedPiece*> pieces;
  for (const Neighbour& n : around) pieces.push_back(n.piece.get());
  pieces.push_back(&own);
  const KeyUnion all(pieces);
  std::vector<VertexUse> use(all.keys.size());
  for (std::size_t p = 0; p < pieces.size(); ++p) {
    for (const Triangle& tri : pieces[p]->triangles) {
      for (const std::uint32_t v : tri) ++use[all.of_piece[p][v]].everywhere;
    }
  }
  // The triangles cut out, the surroundings first (in part order), then the part's own.
  struct CutTriangle {
    std::size_t piece;
    std::size_t t;
  };
  std::vector<CutTriangle> cut_triangles;
  const auto take = [&](std::size_t p, std::size_t t, VertexRole role) {
    for (const std::uint32_t v : pieces[p]->triangles[t]) {
      VertexUse& u = use[all.of_piece[p][v]];
      ++u.in_cut;
      if (strength(role) > strength(u.role)) u.role = role;
      if (u.piece == nullptr) {
        u.piece = pieces[p];
        u.index = v;
      }
    }
    cut_triangles.push_back({p, t});
  };
  for (std::size_t p = 0; p < around.size(); ++p) {
    for (std::size_t t = 0; t < pieces[p]->triangle_count(); ++t) {
      if (pieces[p]->box(t).intersects(reach)) take(p, t, around[p].role);
    }
  }
  const std::size_t surroundings = cut_triangles.size();
  for (std::size_t t = 0; t < own.triangle_count(); ++t) take(pieces.size() - 1, t, VertexRole::free);

  PartCut cut;
  Mesh& m = cut.merged.mesh;
  m.origin = origin;
  std::vector<std::uint32_t> local(all.keys.size(), UINT32_MAX);
  for (std::size_t k = 0; k < all.keys.size(); ++k) {
    const VertexUse& u = use[k];
    if (u.in_cut == 0) continue;
    local[k] = static_cast<std::uint32_t>(cut.keys.size());
    cut.keys.push_back(all.keys[k]);
    cut.positions.push_back(u.piece->positions[u.index]);
    if (!u.piece->sensors.empty()) cut.sensors.push_back(u.piece->sensors[u.index]);
    const bool on_cut_edge = u.in_cut < u.everywhere || !reach.contains(u.piece->positions[u.index]);
    cut.roles.push_back(static_cast<std::uint8_t>(on_cut_edge ? VertexRole::held : u.role));
    append_keyed_vertex(*u.piece, u.index, origin, m);
  }
  for (const auto& [p, t] : cut_triangles) {
    const KeyedPiece& piece = *pieces[p];
    Triangle tri = piece.triangles[t];
    for (std::uint32_t& v : tri) v = local[all.of_piece[p][v]];
    m.triangles.push_back(tri);
    m.triangle_ids.push_back(piece.ids[t]);
    cut.merged.source_acq.push_back(piece.source_acq[t]);
    cut.merged.source_triangle.push_back(piece.source_triangle[t]);
  }
  cut.surroundings.assign(m.triangles.begin(), m.triangles.begin() + static_cast<std::ptrdiff_t>(surroundings));
  return cut;
}

KeyedPiece stitched_piece(const PartCut& cut, std::uint64_t part) {
  const Mesh& m = cut.merged.mesh;
  const std::size_t cut_vertices = cut.keys.size();
  std::vector<std::uint32_t> local(m.vertex_count(), UINT32_MAX);
  for (std::size_t t = cut.surroundings.size(); t < m.triangle_count(); ++t) {
    for (const std::uint32_t v : m.triangles[t]) local[v] = 0;
  }
  KeyedPiece out;
  // In vertex order: the cut's vertices ascend by key, and new ones come after, in order.
  for (std::uint32_t v = 0; v < m.vertex_count(); ++v) {
    if (local[v] == UINT32_MAX) continue;
    local[v] = static_cast<std::uint32_t>(out.keys.size());
    const bool cut_vertex = v < cut_vertices;
    out.keys.push_back(cut_vertex ? cut.keys[v] : kNewVertexKey | part << 32 | (v - cut_vertices));
    // A vertex stitching left where it was keeps its double: no round trip through floats.
    const bool moved = !cut_vertex || m.positions[v] != to_local(cut.positions[v], m.origin);
    out.positions.push_back(moved ? m.origin + Vec3d(m.positions[v]) : cut.positions[v]);
    if (m.has_sensor_positions()) {
      const bool sensor_moved = !cut_vertex || m.sensor_positions[v] != to_local(cut.sensors[v], m.origin);
      out.sensors.push_back(sensor_moved ? m.origin + Vec3d(m.sensor_positions[v]) : cut.sensors[v]);
    }
    if (!m.times.empty()) out.times.push_back(m.times[v]);
    if (!m.intensities.empty()) out.intensities.push_back(m.intensities[v]);
    if (!m.colors.empty()) out.colors.push_back(m.colors[v]);
  }
  for (std::size_t t = cut.surroundings.size(); t < m.triangle_count(); ++t) {
    Triangle tri = m.triangles[t];
    for (std::uint32_t& v : tri) v = local[v];
    out.triangles.push_back(tri);
    out.ids.push_back(m.triangle_ids[t]);
    out.source_acq.push_back(cut.merged.source_acq[t]);
    out.source_triangle.push_back(cut.merged.source_triangle[t]);
  }
  return out;
}

}  // namespace citymesh::mosaic_detail
