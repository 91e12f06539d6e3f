// SPDX-License-Identifier: MIT
#include "tile_plan.h"

#include <fmt/format.h>

#include <algorithm>
#include <charconv>

#include "citymesh/core/error.h"
#include "tile_job.h"

namespace citymesh::app {

std::vector<std::size_t> tile_dependencies(const TileStore& store, std::size_t k) {
  const TileKey key = store.tiles[k].key;
  std::vector<std::size_t> after;
  for (std::int32_t di = -1; di <= 1; ++di) {
    for (std::int32_t dj = -1; dj <= 1; ++dj) {
      const TileKey n{key.i + di, key.j + dj};
      if (tile_phase(n) >= tile_phase(key)) continue;
      const auto it = std::lower_bound(store.tiles.begin(), store.tiles.end(), n,
                                       [](const TileContents& t, TileKey x) { return t.key < x; });
      if (it != store.tiles.end() && it->key == n) after.push_back(static_cast<std::size_t>(it - store.tiles.begin()));
    }
  }
  std::sort(after.begin(), after.end());
  return after;
}

std::uint64_t tile_memory_estimate(const TileContents& tile) { return tile.total() * kBytesPerTileTriangle; }

std::vector<std::size_t> tiles_over_budget(const TileStore& store, const std::vector<std::size_t>& tiles,
                                           std::uint64_t budget) {
  std::vector<std::size_t> over;
  for (const std::size_t k : tiles) {
    if (tile_memory_estimate(store.tiles[k]) > budget) over.push_back(k);
  }
  std::stable_sort(over.begin(), over.end(), [&](std::size_t a, std::size_t b) {
    return store.tiles[a].total() > store.tiles[b].total();
  });
  return over;
}

Subset Subset::parse(const std::string& text) {
  Subset s;
  const auto slash = text.find('/');
  const auto number = [&](std::size_t from, std::size_t to, std::size_t& out) {
    const char* first = text.data() + from;
    const char* last = text.data() + to;
    const auto [end, ec] = std::from_chars(first, last, out);
    return ec == std::errc() && end == last && first != last;
  };
  if (slash == std::string::npos || !number(0, slash, s.index) || !number(slash + 1, text.size(), s.count) ||
      s.count == 0 || s.index == 0 || s.index > s.count) {
    throw UsageError(fmt::format("--subset {}: expected i/N with 1 <= i <= N, e.g. 2/8", text));
  }
  return s;
}

std::string Subset::name() const { return fmt::format("{}/{}", index, count); }

std::vector<std::size_t> subset_tiles(const TileStore& store, const Subset& subset) {
  double total = 0;
  for (const TileContents& t : store.tiles) total += static_cast<double>(t.total());
  // A tile belongs to the subset in whose share of the total its cost's midpoint falls.
  std::vector<std::size_t> tiles;
  double before = 0;
  for (std::size_t k = 0; k < store.tiles.size(); ++k) {
    const double cost = static_cast<double>(store.tiles[k].total());
    const double middle = (before + cost / 2) / std::max(total, 1.0);
    const auto owner = std::min(static_cast<std::size_t>(middle * static_cast<double>(subset.count)), subset.count - 1);
    if (owner == subset.index - 1) tiles.push_back(k);
    before += cost;
  }
  return tiles;
}

std::vector<std::size_t> with_dependencies(const TileStore& store, const std::vector<std::size_t>& tiles) {
  std::vector<std::uint8_t> in(store.tiles.size(), 0);
  std::vector<std::size_t> stack(tiles.begin(), tiles.end());
  while (!stack.empty()) {
    const std::size_t k = stack.back();
    stack.pop_back();
    if (in[k] != 0) continue;
    in[k] = 1;
    for (const std::size_t d : tile_dependencies(store, k)) stack.push_back(d);
  }
  std::vector<std::size_t> out;
  for (std::size_t k = 0; k < in.size(); ++k) {
    if (in[k] != 0) out.push_back(k);
  }
  return out;
}

}  // namespace citymesh::app
