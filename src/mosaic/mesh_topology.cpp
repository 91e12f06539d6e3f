// SPDX-License-Identifier: MIT
#include "mesh_topology.h"

#include <algorithm>
#include <tuple>

#include "citymesh/core/parallel.h"

namespace citymesh::mosaic_detail {

MeshTopology::MeshTopology(MergedMesh& merged, const StitchSurroundings& around, bool own_pieces_apart)
    : merged_(merged),
      around_(around),
      own_pieces_apart_(own_pieces_apart),
      pieces_(own_pieces_apart ? source_pieces(merged) : std::vector<std::int32_t>{}),
      offsets_(merged.mesh.vertex_count() + 1, 0),
      edited_(merged.mesh.vertex_count(), UINT32_MAX) {
  const auto& triangles = merged.mesh.triangles;
  for (const Triangle& tri : triangles) {
    for (const std::uint32_t v : tri) ++offsets_[v + 1];
  }
  for (std::size_t v = 0; v + 1 < offsets_.size(); ++v) offsets_[v + 1] += offsets_[v];
  packed_.resize(offsets_.back());
  std::vector<std::uint32_t> fill(offsets_.begin(), offsets_.end() - 1);
  for (std::uint32_t t = 0; t < triangles.size(); ++t) {
    for (const std::uint32_t v : triangles[t]) packed_[fill[v]++] = t;
  }
}

bool MeshTopology::joinable(std::uint32_t v) const {
  const VertexRole role = role_of(around_.vertex_roles, v);
  if (role == VertexRole::held) return false;
  if (role != VertexRole::later) return true;
  const std::span<const std::uint32_t> around = triangles_of(v);
  return std::any_of(around.begin(), around.end(),
                     [&](std::uint32_t t) { return around_.told_own(t) || !frozen_triangle(t); });
}

std::span<const std::uint32_t> MeshTopology::triangles_of(std::uint32_t v) const {
  if (edited_[v] != UINT32_MAX) return edits_[edited_[v]];
  return {packed_.data() + offsets_[v], packed_.data() + offsets_[v + 1]};
}

std::vector<std::uint32_t>& MeshTopology::edit(std::uint32_t v) {
  if (edited_[v] == UINT32_MAX) {
    const std::span<const std::uint32_t> now = triangles_of(v);
    edited_[v] = static_cast<std::uint32_t>(edits_.size());
    edits_.emplace_back(now.begin(), now.end());
  }
  return edits_[edited_[v]];
}

void MeshTopology::add_triangle(std::uint32_t t, std::int32_t piece) {
  if (own_pieces_apart()) {
    if (pieces_.size() <= t) pieces_.resize(t + 1, kNoSource);
    pieces_[t] = piece;
  }
  for (const std::uint32_t v : triangle(t)) edit(v).push_back(t);
}

std::optional<std::uint32_t> MeshTopology::triangle_with(std::uint32_t from, std::uint32_t to) const {
  for (const std::uint32_t t : triangles_of(from)) {
    const Triangle& tri = triangle(t);
    for (int k = 0; k < 3; ++k) {
      if (tri[k] == from && tri[(k + 1) % 3] == to) return t;
    }
  }
  return std::nullopt;
}

bool MeshTopology::edges_free(std::span<const Triangle> tris, std::span<const std::uint32_t> replaced) const {
  std::vector<std::uint64_t> keys;
  for (const Triangle& tri : tris) {
    for (int k = 0; k < 3; ++k) keys.push_back((std::uint64_t{tri[k]} << 32) | tri[(k + 1) % 3]);
  }
  std::sort(keys.begin(), keys.end());
  if (std::adjacent_find(keys.begin(), keys.end()) != keys.end()) return false;
  return std::none_of(keys.begin(), keys.end(), [&](std::uint64_t key) {
    const auto from = static_cast<std::uint32_t>(key >> 32), to = static_cast<std::uint32_t>(key);
    for (const std::uint32_t t : triangles_of(from)) {
      if (std::find(replaced.begin(), replaced.end(), t) != replaced.end()) continue;
      const Triangle& tri = triangle(t);
      for (int k = 0; k < 3; ++k) {
        if (tri[k] == from && tri[(k + 1) % 3] == to) return true;
      }
    }
    return false;
  });
}

std::int32_t MeshTopology::source_of_vertex(std::uint32_t v) const {
  const std::span<const std::uint32_t> around = triangles_of(v);
  return around.empty() ? kNoSource : merged_.source_acq[around.front()];
}

std::int32_t MeshTopology::piece_of_vertex(std::uint32_t v) const {
  const std::span<const std::uint32_t> around = triangles_of(v);
  return around.empty() ? kNoSource : piece(around.front());
}

double MeshTopology::boundary_length() const { return edges_length(merged_.mesh, boundary_edges()); }

std::vector<EdgeUse> MeshTopology::boundary_edges() const {
  // Each edge {lo, hi} is looked at from lo only: the uses of every edge at lo come from one
  // pass over the triangles around lo (each triangle read three times in all, where a look
  // around lo for each of a triangle's edges read it eighteen times).
  const std::size_t vertices = edited_.size();  // the vertices the lists know
  constexpr std::size_t kVertexGrain = 1 << 15;
  std::vector<std::vector<EdgeUse>> per_block((vertices + kVertexGrain - 1) / kVertexGrain);
  parallel_for_blocks(vertices, kVertexGrain, [&](std::size_t begin, std::size_t end) {
    std::vector<EdgeUse>& out = per_block[begin / kVertexGrain];
    std::vector<EdgeUse> at;  // the uses of the edges whose smaller end is v
    for (auto v = static_cast<std::uint32_t>(begin); v < end; ++v) {
      at.clear();
      const std::span<const std::uint32_t> around = triangles_of(v);
      for (std::size_t i = 0; i < around.size(); ++i) {
        const Triangle& tri = triangle(around[i]);
        // A triangle is listed once per corner at v: one with two there is counted once.
        const int corners_at_v = (tri[0] == v) + (tri[1] == v) + (tri[2] == v);
        const auto seen = around.begin() + static_cast<std::ptrdiff_t>(i);
        if (corners_at_v > 1 && std::find(around.begin(), seen, around[i]) != seen) continue;
        const std::uint32_t t = around[i];
        for (int k = 0; k < 3; ++k) {
          const std::uint32_t a = tri[k], b = tri[(k + 1) % 3];
          if (std::min(a, b) == v) at.push_back({v, std::max(a, b), t});
        }
      }
      std::sort(at.begin(), at.end());
      for (std::size_t i = 0; i < at.size();) {
        std::size_t j = i + 1;
        while (j < at.size() && at[j].hi == at[i].hi) ++j;
        if (j - i == 1) out.push_back(at[i]);
        i = j;
      }
    }
  });
  std::vector<EdgeUse> out;
  for (const auto& block : per_block) out.insert(out.end(), block.begin(), block.end());
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<DirectedEdge> MeshTopology::boundary_half_edges() const {
  // Each half-edge v -> w is looked at from v: a triangle running w -> v uses v, so one pass
  // over the triangles around v lists both the half-edges leaving v and the vertices from
  // which one enters it. Looking each half-edge's reverse up among the triangles around w
  // read every triangle eighteen times, at random: 7 % of a city's final pass (snapping
  // asks four times per part).
  struct Open {
    std::uint32_t triangle, corner, from, to;
  };
  const std::size_t vertices = edited_.size();  // the vertices the lists know
  constexpr std::size_t kVertexGrain = 1 << 15;
  std::vector<std::vector<Open>> per_block((vertices + kVertexGrain - 1) / kVertexGrain);
  parallel_for_blocks(vertices, kVertexGrain, [&](std::size_t begin, std::size_t end) {
    std::vector<Open>& out = per_block[begin / kVertexGrain];
    std::vector<Open> leaving;            // the half-edges v -> w, once each
    std::vector<std::uint32_t> entering;  // the u of every half-edge u -> v
    for (auto v = static_cast<std::uint32_t>(begin); v < end; ++v) {
      const std::span<const std::uint32_t> around = triangles_of(v);
      leaving.clear();
      entering.clear();
      for (std::size_t i = 0; i < around.size(); ++i) {
        const Triangle& tri = triangle(around[i]);
        // A triangle is listed once per corner at v: its corners there are all read at once.
        const int corners_at_v = (tri[0] == v) + (tri[1] == v) + (tri[2] == v);
        const auto seen = around.begin() + static_cast<std::ptrdiff_t>(i);
        if (corners_at_v > 1 && std::find(around.begin(), seen, around[i]) != seen) continue;
        for (std::uint32_t k = 0; k < 3; ++k) {
          if (tri[k] != v) continue;
          leaving.push_back({around[i], k, v, tri[(k + 1) % 3]});
          entering.push_back(tri[(k + 2) % 3]);
        }
      }
      for (const Open& e : leaving) {
        if (std::find(entering.begin(), entering.end(), e.to) == entering.end()) out.push_back(e);
      }
    }
  });
  std::vector<Open> open;
  for (const auto& block : per_block) open.insert(open.end(), block.begin(), block.end());
  // In triangle order, then corner order, as snapping and gap closing walk them.
  std::sort(open.begin(), open.end(), [](const Open& a, const Open& b) {
    return std::tie(a.triangle, a.corner) < std::tie(b.triangle, b.corner);
  });
  std::vector<DirectedEdge> out;
  out.reserve(open.size());
  for (const Open& e : open) out.push_back({e.from, e.to, e.triangle});
  return out;
}

}  // namespace citymesh::mosaic_detail
