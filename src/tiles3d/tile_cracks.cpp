// SPDX-License-Identifier: MIT
#include "tile_cracks.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <map>
#include <utility>

namespace citymesh::tiles3d_detail {

std::uint32_t TileCrackCounter::add_tile(std::uint32_t parent) {
  if (parent != kNoParent) ++tiles_.at(parent).children;
  tiles_.push_back({parent, false, 0, {}});
  return static_cast<std::uint32_t>(tiles_.size() - 1);
}

std::vector<TileCrackCounter::EdgeKey> TileCrackCounter::edges_of(std::span<const Vec3f> positions,
                                                                  std::span<const Triangle> triangles) {
  const auto corner = [&](std::uint32_t v) { return position_bits(positions[v]); };
  std::vector<EdgeKey> edges;
  edges.reserve(3 * triangles.size());
  for (const Triangle& t : triangles) {
    for (std::size_t k = 0; k < 3; ++k) {
      std::array<std::uint32_t, 3> a = corner(t[k]), b = corner(t[(k + 1) % 3]);
      if (a == b) continue;  // a corner quantized onto its neighbour: no edge
      if (b < a) std::swap(a, b);
      edges.push_back({a[0], a[1], a[2], b[0], b[1], b[2]});
    }
  }
  std::sort(edges.begin(), edges.end());
  return edges;
}

void TileCrackCounter::set_content(std::uint32_t tile, std::span<const Vec3f> positions,
                                   std::span<const Triangle> triangles) {
  const std::vector<EdgeKey> edges = edges_of(positions, triangles);
  Tile& out = tiles_.at(tile);
  out.has_content = true;
  out.open.clear();
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i + 1;
    while (j < edges.size() && edges[j] == edges[i]) ++j;
    if (j - i == 1) out.open.push_back(edges[i]);
    i = j;
  }
}

std::vector<std::uint32_t> TileCrackCounter::chain(std::uint32_t tile) const {
  std::vector<std::uint32_t> out;
  for (std::uint32_t t = tile; t != kNoParent; t = tiles_[t].parent) out.push_back(t);
  return out;
}

double TileCrackCounter::length(const EdgeKey& e) {
  double sum = 0;
  for (std::size_t k = 0; k < 3; ++k) {
    const double d = static_cast<double>(std::bit_cast<float>(e[k])) - static_cast<double>(std::bit_cast<float>(e[k + 3]));
    sum += d * d;
  }
  return std::sqrt(sum);
}

TileCracks TileCrackCounter::count(const TileContentSource& reload) const {
  // Every leaf's open edges, by edge: an edge open in exactly two leaves is a seam.
  std::vector<std::pair<EdgeKey, std::uint32_t>> leaf_edges;
  for (std::uint32_t t = 0; t < tiles_.size(); ++t) {
    if (!tiles_[t].has_content || tiles_[t].children > 0) continue;
    for (const EdgeKey& e : tiles_[t].open) leaf_edges.emplace_back(e, t);
  }
  std::sort(leaf_edges.begin(), leaf_edges.end());
  TileCracks out;
  std::map<std::uint32_t, std::vector<std::pair<EdgeKey, double>>> missing;  ///< from a tile's open edges
  for (std::size_t i = 0; i < leaf_edges.size();) {
    std::size_t j = i + 1;
    while (j < leaf_edges.size() && leaf_edges[j].first == leaf_edges[i].first) ++j;
    if (j - i == 2 && leaf_edges[i].second != leaf_edges[i + 1].second) {
      const EdgeKey& edge = leaf_edges[i].first;
      const double len = length(edge);
      ++out.seam_edges;
      out.seam_length += len;
      const std::vector<std::uint32_t> a = chain(leaf_edges[i].second), b = chain(leaf_edges[i + 1].second);
      // A tile above one of the two leaves and not above the other is drawn beside the other
      // one: it must have the seam on its border.
      for (const auto& [own, other] : {std::pair{&a, &b}, std::pair{&b, &a}}) {
        for (std::size_t k = 1; k < own->size(); ++k) {
          const std::uint32_t t = (*own)[k];
          if (!tiles_[t].has_content || std::find(other->begin(), other->end(), t) != other->end()) continue;
          if (!std::binary_search(tiles_[t].open.begin(), tiles_[t].open.end(), edge)) missing[t].emplace_back(edge, len);
        }
      }
    }
    i = j;
  }
  for (const auto& [t, edges] : missing) {
    const TileContent content = reload(t);
    const std::vector<EdgeKey> all = edges_of(content.positions, content.triangles);
    double length_in_tile = 0;
    for (const auto& [edge, len] : edges) {
      if (std::binary_search(all.begin(), all.end(), edge)) continue;
      ++out.crack_edges;
      out.crack_length += len;
      length_in_tile += len;
    }
    if (length_in_tile > 0) out.by_tile.emplace_back(t, length_in_tile);
  }
  std::stable_sort(out.by_tile.begin(), out.by_tile.end(),
                   [](const auto& a, const auto& b) { return a.second > b.second; });
  return out;
}

}  // namespace citymesh::tiles3d_detail
