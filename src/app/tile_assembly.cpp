// SPDX-License-Identifier: MIT
#include "tile_assembly.h"

#include <fmt/format.h>

#include <algorithm>
#include <tuple>
#include <unordered_map>

#include "citymesh/core/error.h"
#include "citymesh/mosaic/mosaic.h"

namespace citymesh::app {

TileAssembly::TileAssembly(const TileStore& store, bool labels) : store_(store), labels_(labels) {
  index_.offsets.assign(1, 0);
  for (const std::uint64_t n : store.triangles) index_.offsets.push_back(index_.offsets.back() + n);
  if (index_.size() > UINT32_MAX) {
    throw ProcessingError(fmt::format("{} triangles in all: global ids are 32-bit", index_.size()));
  }
  if (!labels_) return;
  ChangeResult& c = change_.emplace();
  c.index = index_;
  const std::size_t n = index_.size();
  c.state.assign(n, TriangleState::single);
  c.first_seen.assign(n, TimePoint{});
  c.last_seen.assign(n, TimePoint{});
  c.sustainable.assign(n, 0);
  c.kept.assign(n, 0);
  c.refutes.assign(n, 0);
}

void TileAssembly::add(TileResult result) {
  const auto global = [&](std::uint32_t a, std::uint32_t t) -> std::uint32_t {
    if (a >= store_.triangles.size() || t >= store_.triangles[a]) {
      throw ProcessingError(fmt::format("tile {}: triangle {} of acquisition {} is not in the tile store",
                                        result.key.name(), t, a));
    }
    return static_cast<std::uint32_t>(index_.offsets[a] + t);
  };
  for (const OwnedLabel& l : result.labels) {
    const std::uint32_t g = global(l.acquisition, l.index);
    ++owned_;
    candidates_ += l.kept;
    seen_through_ += (l.notes & kNoteSeenThrough) != 0 ? 1 : 0;
    filled_ += (l.notes & kNoteFilled) != 0 ? 1 : 0;
    fill_left_out_ += (l.notes & kNoteFillLeftOut) != 0 ? 1 : 0;
    if (!change_) continue;
    ChangeResult& c = *change_;
    c.state[g] = l.state;
    c.kept[g] = l.kept;
    c.sustainable[g] = l.sustainable;
    c.refutes[g] = l.refutes;
    c.first_seen[g] = TimePoint(Duration(l.first_ms));
    c.last_seen[g] = TimePoint(Duration(l.last_ms));
  }
  if (change_) {
    for (const LabelPair& p : result.pairs) {
      change_->consistent_pairs.emplace_back(global(p.a_acquisition, p.a_index), global(p.b_acquisition, p.b_index));
    }
  }
  for (TilePiece& p : result.selected) {
    if (p.triangle_count() > 0) pieces_.push_back(std::move(p));
  }
}

MergedMesh TileAssembly::merged() const {
  // (acquisition, triangle index, piece, triangle in piece): the output order is the input's.
  std::vector<std::tuple<std::uint32_t, std::uint32_t, std::uint32_t, std::uint32_t>> order;
  bool intensities = true, colors = true;
  for (std::uint32_t p = 0; p < pieces_.size(); ++p) {
    const TilePiece& piece = pieces_[p];
    intensities = intensities && !piece.mesh.intensities.empty();
    colors = colors && !piece.mesh.colors.empty();
    for (std::uint32_t t = 0; t < piece.triangle_count(); ++t) {
      order.emplace_back(piece.mesh.triangle_ids[t].acquisition, piece.triangle_index[t], p, t);
    }
  }
  std::sort(order.begin(), order.end());
  MergedMesh out;
  Mesh& m = out.mesh;
  if (!order.empty()) {
    const TilePiece& first = pieces_[std::get<2>(order.front())];
    m.origin = whole_metre_origin(first.mesh.world_position(first.mesh.triangles[std::get<3>(order.front())][0]));
  }
  std::unordered_map<std::uint64_t, std::uint32_t> vertex;  // (acquisition, vertex id) -> merged vertex
  vertex.reserve(order.size());  // about one vertex for every two triangles; no rehash on the way
  for (const auto& [a, index, p, t] : order) {
    const TilePiece& piece = pieces_[p];
    Triangle tri{};
    for (std::size_t c = 0; c < 3; ++c) {
      const std::uint32_t v = piece.mesh.triangles[t][c];
      const std::uint64_t key = (std::uint64_t{a} << 32) | piece.vertex_ids[v];
      const auto [it, added] = vertex.try_emplace(key, static_cast<std::uint32_t>(m.positions.size()));
      if (added) {
        m.positions.push_back(to_local(piece.mesh.world_position(v), m.origin));
        m.sensor_positions.push_back(to_local(piece.mesh.world_sensor_position(v), m.origin));
        if (intensities) m.intensities.push_back(piece.mesh.intensities[v]);
        if (colors) m.colors.push_back(piece.mesh.colors[v]);
      }
      tri[c] = it->second;
    }
    m.triangles.push_back(tri);
    m.triangle_ids.push_back(piece.mesh.triangle_ids[t]);
    out.source_acq.push_back(static_cast<std::int32_t>(a));
    out.source_triangle.push_back(static_cast<std::int32_t>(index));
  }
  return out;
}

ChangeResult TileAssembly::change() const {
  if (!change_) throw ProcessingError("tile assembly: labels were not gathered");
  if (owned_ != index_.size()) {
    throw ProcessingError(fmt::format("tile assembly: {} triangles owned by the tiles, the input has {}", owned_,
                                      index_.size()));
  }
  ChangeResult c = *change_;
  std::sort(c.consistent_pairs.begin(), c.consistent_pairs.end());
  c.consistent_pairs.erase(std::unique(c.consistent_pairs.begin(), c.consistent_pairs.end()), c.consistent_pairs.end());
  c.stats.triangles = index_.size();
  c.stats.consistent_pairs = c.consistent_pairs.size();
  return c;
}

}  // namespace citymesh::app
