// SPDX-License-Identifier: MIT
#include "restricted_energy.h"

#include <algorithm>
#include <iterator>

#include "citymesh/core/error.h"
#include "citymesh/core/parallel.h"

namespace citymesh::mosaic_detail {

PairIndex::PairIndex(const BinaryEnergy& e) : offsets(e.size() + 1, 0) {
  if (e.size() >= kAtJ) throw ProcessingError("energy: too many variables");
  const std::size_t n = e.size();
  const PairList& terms = e.pairs;
  // Blocks of consecutive pairs, each counted and then filled on its own thread, at entries
  // after those of the blocks before it: every row lists its pairs in increasing order, as a
  // single pass would, whatever the number of blocks (the serial pass was half the index's time).
  constexpr std::size_t kMinBlockPairs = 1 << 16;
  const std::size_t blocks =
      std::clamp<std::size_t>(terms.size() / kMinBlockPairs, 1, std::min(4u, available_threads()));
  const auto block_begin = [&](std::size_t b) { return terms.size() * b / blocks; };
  std::vector<std::vector<std::uint32_t>> at(blocks, std::vector<std::uint32_t>(n, 0));
  parallel_for_blocks(blocks, 1, [&](std::size_t begin, std::size_t end) {
    for (std::size_t b = begin; b < end; ++b) {
      for (std::size_t k = block_begin(b); k < block_begin(b + 1); ++k) {
        const auto [i, j] = terms.variables(k);
        if (i == j) throw ProcessingError("energy: a pair joins a variable to itself");
        ++at[b][i];
        ++at[b][j];
      }
    }
  });
  for (std::size_t v = 0; v < n; ++v) {
    std::uint32_t row = offsets[v];
    for (std::vector<std::uint32_t>& counts : at) {
      const std::uint32_t count = counts[v];
      counts[v] = row;  // from here on: where block b's next entry of v goes
      row += count;
    }
    offsets[v + 1] = row;
  }
  ends.resize(offsets.back());
  value_rows.resize(offsets.back());
  // Each of the energy's rows twice: seen from i, and from j (e01 and e10 swapped).
  const std::span<const std::array<double, 4>> shared = terms.values();
  rows.resize(2 * shared.size());
  for (std::size_t r = 0; r < shared.size(); ++r) {
    const auto& [e00, e01, e10, e11] = shared[r];
    rows[2 * r] = {e00, e01, e10, e11};
    rows[2 * r + 1] = {e00, e10, e01, e11};
  }
  parallel_for_blocks(blocks, 1, [&](std::size_t begin, std::size_t end) {
    for (std::size_t b = begin; b < end; ++b) {
      std::vector<std::uint32_t>& fill = at[b];
      for (std::size_t k = block_begin(b); k < block_begin(b + 1); ++k) {
        const auto [i, j] = terms.variables(k);
        const std::uint32_t row = 2 * terms.row(k);
        ends[fill[i]] = j;
        value_rows[fill[i]++] = row;
        ends[fill[j]] = i | kAtJ;
        value_rows[fill[j]++] = row + 1;
      }
    }
  });
}

BinaryEnergy restricted(const BinaryEnergy& e, const PairIndex& index, std::span<const std::int8_t> x,
                        std::span<const std::uint32_t> open, std::vector<std::uint32_t>& to_local) {
  BinaryEnergy r;
  r.unary.resize(open.size());
  r.pairs.reserve(2 * open.size());
  for (std::uint32_t l = 0; l < open.size(); ++l) to_local[open[l]] = l;
  for (std::uint32_t l = 0; l < open.size(); ++l) {
    const std::uint32_t v = open[l];
    r.unary[l] = e.unary[v];
    for (std::uint32_t entry = index.offsets[v]; entry < index.offsets[v + 1]; ++entry) {
      const std::uint32_t end = index.ends[entry], o = PairIndex::variable(end);
      const auto& w = index.values(entry);  // w[2 * (this end) + (other end)]
      if (to_local[o] != UINT32_MAX) {
        // Both ends open: the pair is taken once, from its i end.
        if ((end & PairIndex::kAtJ) == 0) r.pairs.push_back({l, to_local[o], w[0], w[1], w[2], w[3]});
        continue;
      }
      const std::size_t other = x[o] != 0 ? 1 : 0;
      r.unary[l][0] += w[other];
      r.unary[l][1] += w[2 + other];
    }
  }
  for (const std::uint32_t v : open) to_local[v] = UINT32_MAX;
  return r;
}

namespace {

/// Per variable of `all`, 1 when `test` holds for it: a read-only question per variable, so
/// asked in parallel.
template <class Test>
std::vector<std::uint8_t> flags_of(std::span<const std::uint32_t> all, const Test& test) {
  std::vector<std::uint8_t> flags(all.size());
  parallel_for_blocks(all.size(), 8192, [&](std::size_t begin, std::size_t end) {
    for (std::size_t l = begin; l < end; ++l) flags[l] = test(all[l]) ? 1 : 0;
  });
  return flags;
}

}  // namespace

std::vector<std::uint32_t> grow_region(const PairIndex& index, std::vector<std::uint32_t> seeds,
                                       std::span<const std::uint8_t> open, std::uint32_t hops,
                                       std::vector<std::uint8_t>& mark) {
  std::vector<std::uint32_t> region = std::move(seeds);
  for (const std::uint32_t v : region) mark[v] = 1;
  std::size_t ring_begin = 0;
  for (std::uint32_t hop = 0; hop < hops && ring_begin < region.size(); ++hop) {
    const std::size_t ring_end = region.size();
    for (std::size_t r = ring_begin; r < ring_end; ++r) {
      for (std::uint32_t entry = index.offsets[region[r]]; entry < index.offsets[region[r] + 1]; ++entry) {
        const std::uint32_t o = PairIndex::variable(index.ends[entry]);
        if (open[o] == 0 || mark[o] != 0) continue;
        mark[o] = 1;
        region.push_back(o);
      }
    }
    ring_begin = ring_end;
  }
  // A dense region is sorted by a scan of the marks over its span: a later sweep's regions
  // hold tens of thousands of variables, and sorting them took half the walk.
  if (region.empty()) return region;
  const auto [lo, hi] = std::minmax_element(region.begin(), region.end());
  const std::size_t first = *lo, last = *hi;
  if (last - first > 32 * region.size()) {
    for (const std::uint32_t v : region) mark[v] = 0;
    std::sort(region.begin(), region.end());
    return region;
  }
  region.clear();
  for (std::size_t v = first; v <= last; ++v) {
    if (mark[v] == 0) continue;
    mark[v] = 0;
    region.push_back(static_cast<std::uint32_t>(v));
  }
  return region;
}

std::vector<std::uint32_t> seam_region(const PairIndex& index, std::span<const std::int8_t> x,
                                       std::span<const std::uint32_t> all, std::span<const std::uint8_t> open,
                                       std::uint32_t hops, std::vector<std::uint8_t>& mark) {
  const auto on_seam = [&](std::uint32_t v) {
    for (std::uint32_t entry = index.offsets[v]; entry < index.offsets[v + 1]; ++entry) {
      const auto& w = index.values(entry);
      if (w[1] + w[2] > w[0] + w[3] && x[PairIndex::variable(index.ends[entry])] != x[v]) return true;
    }
    return false;
  };
  const std::vector<std::uint8_t> seam_flag = flags_of(all, on_seam);
  std::vector<std::uint32_t> seeds;
  for (std::size_t l = 0; l < all.size(); ++l) {
    if (seam_flag[l] != 0) seeds.push_back(all[l]);
  }
  return grow_region(index, std::move(seeds), open, hops, mark);
}

SlabSplit split_by_slab(const PairIndex& index, std::span<const std::uint32_t> all, std::span<const std::uint8_t> open,
                        std::span<const std::uint32_t> slab, std::uint32_t slabs) {
  const auto on_border = [&](std::uint32_t v) {
    for (std::uint32_t entry = index.offsets[v]; entry < index.offsets[v + 1]; ++entry) {
      const std::uint32_t o = PairIndex::variable(index.ends[entry]);
      if (open[o] != 0 && slab[o] != slab[v]) return true;
    }
    return false;
  };
  const std::vector<std::uint8_t> border_flag = flags_of(all, on_border);
  SlabSplit out;
  out.interior.resize(slabs);
  for (std::size_t l = 0; l < all.size(); ++l) {
    if (border_flag[l] != 0) {
      out.border.push_back(all[l]);
    } else {
      out.interior[slab[all[l]]].push_back(all[l]);
    }
  }
  return out;
}

}  // namespace citymesh::mosaic_detail
