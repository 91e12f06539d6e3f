// SPDX-License-Identifier: MIT
#include "citymesh/core/keyed_piece.h"

#include <fmt/format.h>

#include <algorithm>
#include <functional>

#include "citymesh/core/checksum.h"
#include "citymesh/core/error.h"
#include "citymesh/core/key_union.h"

namespace citymesh {

namespace {

/// Which optional attributes a piece carries, one bit each.
unsigned attribute_bits(const KeyedPiece& p) {
  return (p.sensors.empty() ? 0u : 1u) | (p.times.empty() ? 0u : 2u) | (p.intensities.empty() ? 0u : 4u) |
         (p.colors.empty() ? 0u : 8u);
}

}  // namespace

Box3d KeyedPiece::box(std::size_t t) const {
  Box3d b;
  for (const std::uint32_t v : triangles[t]) b.extend(positions[v]);
  return b;
}

Box3d KeyedPiece::box() const {
  Box3d b;
  for (std::size_t t = 0; t < triangle_count(); ++t) b.extend(box(t));
  return b;
}

void KeyedPiece::append_vertex(const KeyedPiece& from, std::uint32_t v, std::uint64_t key) {
  keys.push_back(key);
  positions.push_back(from.positions[v]);
  if (!from.sensors.empty()) sensors.push_back(from.sensors[v]);
  if (!from.times.empty()) times.push_back(from.times[v]);
  if (!from.intensities.empty()) intensities.push_back(from.intensities[v]);
  if (!from.colors.empty()) colors.push_back(from.colors[v]);
}

void KeyedPiece::append_mesh_vertex(const Mesh& m, std::uint32_t v, std::uint64_t key) {
  keys.push_back(key);
  positions.push_back(m.world_position(v));
  if (m.has_sensor_positions()) sensors.push_back(m.world_sensor_position(v));
  if (!m.times.empty()) times.push_back(m.times[v]);
  if (!m.intensities.empty()) intensities.push_back(m.intensities[v]);
  if (!m.colors.empty()) colors.push_back(m.colors[v]);
}

void KeyedPiece::append_triangle(const KeyedPiece& from, std::size_t t, const Triangle& corners) {
  triangles.push_back(corners);
  ids.push_back(from.ids[t]);
  source_acq.push_back(from.source_acq[t]);
  source_triangle.push_back(from.source_triangle[t]);
}

void KeyedPiece::check(std::string_view what) const {
  const std::size_t n = keys.size(), tris = triangles.size();
  const auto optional_size = [&](std::size_t size) { return size == 0 || size == n; };
  bool ok = positions.size() == n && optional_size(sensors.size()) && optional_size(times.size()) &&
            optional_size(intensities.size()) && optional_size(colors.size()) && ids.size() == tris &&
            source_acq.size() == tris && source_triangle.size() == tris &&
            std::adjacent_find(keys.begin(), keys.end(), std::greater_equal<>()) == keys.end();
  for (std::size_t t = 0; ok && t < tris; ++t) {
    ok = triangles[t][0] < n && triangles[t][1] < n && triangles[t][2] < n;
  }
  if (!ok) throw ProcessingError(fmt::format("{}: the part's arrays disagree or its vertices are out of order", what));
}

KeyedPiece subset(const KeyedPiece& piece, std::span<const std::uint32_t> triangles) {
  std::vector<std::uint32_t> local(piece.vertex_count(), UINT32_MAX);
  for (const std::uint32_t t : triangles) {
    for (const std::uint32_t v : piece.triangles[t]) local[v] = 0;
  }
  KeyedPiece out;
  for (std::uint32_t v = 0; v < piece.vertex_count(); ++v) {
    if (local[v] == UINT32_MAX) continue;
    local[v] = static_cast<std::uint32_t>(out.vertex_count());
    out.append_vertex(piece, v, piece.keys[v]);
  }
  for (const std::uint32_t t : triangles) {
    const Triangle& tri = piece.triangles[t];
    out.append_triangle(piece, t, {local[tri[0]], local[tri[1]], local[tri[2]]});
  }
  return out;
}

KeyedPiece merge_pieces(std::span<const KeyedPiece* const> pieces) {
  std::vector<const KeyedPiece*> used;
  for (const KeyedPiece* p : pieces) {
    if (p->vertex_count() == 0) continue;
    if (!used.empty() && attribute_bits(*p) != attribute_bits(*used.front())) {
      throw ProcessingError("merging parts of an output: the parts carry different vertex attributes");
    }
    used.push_back(p);
  }
  const KeyUnion all(used);
  // Each key's vertex from the first piece holding it.
  std::vector<std::pair<const KeyedPiece*, std::uint32_t>> source(all.keys.size(), {nullptr, 0});
  for (std::size_t p = 0; p < used.size(); ++p) {
    for (std::uint32_t v = 0; v < used[p]->vertex_count(); ++v) {
      auto& s = source[all.of_piece[p][v]];
      if (s.first == nullptr) s = {used[p], v};
    }
  }
  KeyedPiece out;
  for (std::size_t k = 0; k < all.keys.size(); ++k) out.append_vertex(*source[k].first, source[k].second, all.keys[k]);
  for (std::size_t p = 0; p < used.size(); ++p) {
    for (std::size_t t = 0; t < used[p]->triangle_count(); ++t) {
      const Triangle& tri = used[p]->triangles[t];
      const std::vector<std::uint32_t>& at = all.of_piece[p];
      out.append_triangle(*used[p], t, {at[tri[0]], at[tri[1]], at[tri[2]]});
    }
  }
  return out;
}

std::uint64_t keyed_piece_digest(const KeyedPiece& piece) { return keyed_piece_digest(piece, piece.keys, {}); }

std::uint64_t keyed_piece_digest(const KeyedPiece& piece, std::span<const std::uint64_t> head,
                                 std::span<const std::uint64_t> tail) {
  BulkChecksum sum;
  sum.add_value(std::uint64_t{head.size() + tail.size()});  // as add_array of the keys whole
  sum.add(head.data(), head.size_bytes());
  sum.add(tail.data(), tail.size_bytes());
  sum.add_array(std::span(piece.positions));
  sum.add_array(std::span(piece.sensors));
  sum.add_array(std::span(piece.times));
  sum.add_array(std::span(piece.intensities));
  sum.add_array(std::span(piece.colors));
  sum.add_array(std::span(piece.triangles));
  sum.add_array(std::span(piece.ids));
  sum.add_array(std::span(piece.source_acq));
  sum.add_array(std::span(piece.source_triangle));
  return sum.value();
}

}  // namespace citymesh
