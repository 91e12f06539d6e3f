// SPDX-License-Identifier: MIT
#include "tile_plan.h"

#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <cstdint>
#include <utility>

#include "citymesh/core/checksum.h"
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
      if (const TileContents* t = store.find(n)) after.push_back(static_cast<std::size_t>(t - store.tiles.data()));
    }
  }
  std::sort(after.begin(), after.end());
  return after;
}

TileDigests tile_digests(const TileStore& store, std::uint64_t settings, std::span<const std::uint64_t> identities) {
  TileDigests digests{std::vector<std::uint64_t>(store.tiles.size()), std::vector<std::uint64_t>(store.tiles.size())};
  // A tile's dependencies are of earlier phases: phase by phase, their digests are known.
  for (int phase = 0; phase < kTilePhases; ++phase) {
    for (std::size_t k = 0; k < store.tiles.size(); ++k) {
      const TileContents& tile = store.tiles[k];
      if (tile_phase(tile.key) != phase) continue;
      if (tile.triangles.size() > identities.size()) {
        throw ProcessingError(fmt::format("tile {} holds {} acquisitions, {} are fingerprinted", tile.key.name(),
                                          tile.triangles.size(), identities.size()));
      }
      // The inputs name the passes by identity, in their order (by time): the same for a
      // tile whose passes were renumbered by a pass delivered late elsewhere.
      std::vector<std::uint64_t> words{settings, static_cast<std::uint32_t>(tile.key.i),
                                       static_cast<std::uint32_t>(tile.key.j)};
      const std::vector<std::uint32_t> passes = tile.passes();
      for (const std::uint32_t a : passes) {
        const auto& counts = tile.triangles[a];
        words.insert(words.end(), {identities[a], counts[0], counts[1], counts[2]});
      }
      digests.inputs[k] = fnv1a(words.data(), words.size() * sizeof(std::uint64_t));
      // The result holds the passes' indices: under another numbering it is another result.
      words.insert(words.end(), passes.begin(), passes.end());
      for (const std::size_t d : tile_dependencies(store, k)) words.push_back(digests.result[d]);
      digests.result[k] = fnv1a(words.data(), words.size() * sizeof(std::uint64_t));
    }
  }
  return digests;
}

std::vector<std::uint64_t> tile_priorities(const TileStore& store, const std::vector<std::size_t>& tiles,
                                           std::span<const std::uint8_t> theirs) {
  std::uint64_t own_first = 1;  // above every tile's cost
  for (const std::size_t k : tiles) own_first += store.tiles[k].total();
  std::vector<std::uint64_t> priorities;
  for (const std::size_t k : tiles) {
    priorities.push_back(store.tiles[k].total() + (!theirs.empty() && theirs[k] != 0 ? 0 : own_first));
  }
  return priorities;
}

std::uint64_t tile_memory_estimate(const TileContents& tile) { return tile.total() * kBytesPerTileTriangle; }

std::vector<std::size_t> tiles_over_budget(const TileStore& store, const std::vector<std::size_t>& tiles,
                                           std::uint64_t budget) {
  std::vector<std::size_t> over;
  for (const std::size_t k : tiles) {
    if (tile_over_budget(store.tiles[k], budget)) over.push_back(k);
  }
  std::stable_sort(over.begin(), over.end(),
                   [&](std::size_t a, std::size_t b) { return store.tiles[a].total() > store.tiles[b].total(); });
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

namespace {

/// A subset redoes about one column of tiles along a cut between columns (a tile waits for
/// the column before it only for phases 0 and 1, which wait for nothing across), and two to
/// three rows along a cut between rows (tile_phase() takes the column's parity as the major
/// bit, so a row of phase 2 and 3 tiles waits for rows on both sides): the cost of a cut
/// along a row, per tile of its length, against one along a column.
constexpr double kRowCutCost = 2.5;

/// Of `tiles` (indices into store.tiles) split into `parts` subsets of about equal cost, the
/// subset `wanted` (0-based): halves of the subset count, cut across the longer side of the
/// tiles' extent (in grid cells, a row weighing kRowCutCost), recursively, following only the
/// half that holds `wanted` (so that any subset count costs a few sorts of the tiles). Compact
/// subsets have short borders, and a subset redoes only the tiles across its border that it
/// waits for.
std::vector<std::size_t> bisect(const TileStore& store, std::vector<std::size_t> tiles, std::size_t parts,
                                std::size_t wanted) {
  while (parts > 1 && !tiles.empty()) {
    std::int64_t i0 = INT64_MAX, i1 = INT64_MIN, j0 = INT64_MAX, j1 = INT64_MIN;
    double total = 0;
    for (const std::size_t k : tiles) {
      const TileKey key = store.tiles[k].key;
      i0 = std::min<std::int64_t>(i0, key.i), i1 = std::max<std::int64_t>(i1, key.i);
      j0 = std::min<std::int64_t>(j0, key.j), j1 = std::max<std::int64_t>(j1, key.j);
      total += static_cast<double>(store.tiles[k].total());
    }
    // Between columns (sorted along i) when that cut is no longer than one between rows;
    // whole cells of the other axis stay together, so the cut runs along a grid line where
    // it can.
    const bool along_i = kRowCutCost * static_cast<double>(i1 - i0 + 1) >= static_cast<double>(j1 - j0 + 1);
    std::sort(tiles.begin(), tiles.end(), [&](std::size_t a, std::size_t b) {
      const TileKey x = store.tiles[a].key, y = store.tiles[b].key;
      return along_i ? x < y : std::pair(x.j, x.i) < std::pair(y.j, y.i);
    });
    const std::size_t first_parts = parts / 2;
    const double target = total * static_cast<double>(first_parts) / static_cast<double>(parts);
    // A tile goes to the first half when its cost's midpoint falls before the target.
    std::size_t cut = 0;
    double before = 0;
    while (cut < tiles.size()) {
      const auto cost = static_cast<double>(store.tiles[tiles[cut]].total());
      if (before + cost / 2 > target) break;
      before += cost;
      ++cut;
    }
    const auto middle = tiles.begin() + static_cast<std::ptrdiff_t>(cut);
    if (wanted < first_parts) {
      tiles.erase(middle, tiles.end());
      parts = first_parts;
    } else {
      tiles.erase(tiles.begin(), middle);
      parts -= first_parts;
      wanted -= first_parts;
    }
  }
  std::sort(tiles.begin(), tiles.end());
  return tiles;
}

}  // namespace

std::vector<std::size_t> subset_tiles(const TileStore& store, const Subset& subset) {
  std::vector<std::size_t> tiles(store.tiles.size());
  for (std::size_t k = 0; k < tiles.size(); ++k) tiles[k] = k;
  return bisect(store, std::move(tiles), std::max<std::size_t>(subset.count, 1), subset.index - 1);
}

std::vector<std::vector<std::size_t>> all_subsets(const TileStore& store, std::size_t count) {
  std::vector<std::vector<std::size_t>> out;
  for (std::size_t i = 1; i <= count; ++i) out.push_back(subset_tiles(store, {i, count}));
  return out;
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
