// SPDX-License-Identifier: MIT
#include "restricted_energy.h"

#include <algorithm>
#include <iterator>

#include "citymesh/core/error.h"
#include "citymesh/core/parallel.h"

namespace citymesh::mosaic_detail {

namespace {

/// Per block of terms, per variable: a count, then where the block's next item of the
/// variable goes.
using BlockCounts = std::vector<std::vector<std::uint32_t>>;

/// Turns per-block counts into cursors: block b's items of variable v go after those of v in
/// blocks before b, and after those of the variables before v. Returns the offsets (n + 1).
std::vector<std::uint32_t> counts_to_cursors(BlockCounts& counts, std::size_t n) {
  std::vector<std::uint32_t> offsets(n + 1, 0);
  std::uint64_t at = 0;
  for (std::size_t v = 0; v < n; ++v) {
    offsets[v] = static_cast<std::uint32_t>(at);
    for (std::vector<std::uint32_t>& block : counts) {
      const std::uint32_t count = block[v];
      block[v] = static_cast<std::uint32_t>(at);
      at += count;
    }
    if (at >= PairIndex::kAtJ) throw ProcessingError("energy: too many pair terms");
  }
  offsets[n] = static_cast<std::uint32_t>(at);
  return offsets;
}

}  // namespace

PairIndex::PairIndex(const BinaryEnergy& e) : rows_(e.pairs.values()) {
  if (e.size() >= kAtJ) throw ProcessingError("energy: too many variables");
  const std::size_t n = e.size();
  const PairList& terms = e.pairs;
  // Blocks of consecutive pairs, each counted and then filled on its own thread, at entries
  // after those of the blocks before it: every row lists its pairs in increasing order, as a
  // single pass would, whatever the number of blocks (the serial pass was half the index's
  // time). A run starts where a variable's row changes within a block: a block's first run of
  // a variable may repeat the row of the block before's last, which reads the same.
  constexpr std::size_t kMinBlockPairs = 1 << 16;
  const std::size_t blocks =
      std::clamp<std::size_t>(terms.size() / kMinBlockPairs, 1, std::min(4u, available_threads()));
  const auto block_begin = [&](std::size_t b) { return terms.size() * b / blocks; };
  BlockCounts entry_at(blocks, std::vector<std::uint32_t>(n, 0)), run_at = entry_at;
  BlockCounts last_row(blocks, std::vector<std::uint32_t>(n, UINT32_MAX));
  // visit(b, i, j, row) for each term of each block, the blocks on their own threads.
  const auto walk_blocks = [&](const auto& visit) {
    parallel_for_blocks(blocks, 1, [&](std::size_t begin, std::size_t end) {
      for (std::size_t b = begin; b < end; ++b) {
        const auto last = terms.begin() + block_begin(b + 1);  // made once: it finds its row by bisection
        for (auto term = terms.begin() + block_begin(b); term != last; ++term) {
          const auto [i, j] = term.variables();
          visit(b, i, j, term.row());
        }
      }
    });
  };
  walk_blocks([&](std::size_t b, std::uint32_t i, std::uint32_t j, std::uint32_t row) {
    if (i == j) throw ProcessingError("energy: a pair joins a variable to itself");
    for (const std::uint32_t v : {i, j}) {
      ++entry_at[b][v];
      if (last_row[b][v] != row) ++run_at[b][v];
      last_row[b][v] = row;
    }
  });
  offsets_ = counts_to_cursors(entry_at, n);
  run_offsets_ = counts_to_cursors(run_at, n);
  ends_.resize(offsets_.back());
  runs_.resize(run_offsets_.back());
  for (std::vector<std::uint32_t>& rows : last_row) std::fill(rows.begin(), rows.end(), UINT32_MAX);
  walk_blocks([&](std::size_t b, std::uint32_t i, std::uint32_t j, std::uint32_t row) {
    const auto add = [&](std::uint32_t v, std::uint32_t other_end) {
      if (last_row[b][v] != row) runs_[run_at[b][v]++] = {entry_at[b][v], row};
      last_row[b][v] = row;
      ends_[entry_at[b][v]++] = other_end;
    };
    add(i, j);
    add(j, i | kAtJ);
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
    index.for_each_term(v, [&](std::uint32_t end, const PairIndex::Values& w) {
      const std::uint32_t o = PairIndex::variable(end);
      if (to_local[o] != UINT32_MAX) {
        // Both ends open: the pair is taken once, from its i end.
        if ((end & PairIndex::kAtJ) == 0) r.pairs.push_back({l, to_local[o], w[0], w[1], w[2], w[3]});
        return;
      }
      const std::size_t other = x[o] != 0 ? 1 : 0;
      r.unary[l][0] += w[other];
      r.unary[l][1] += w[2 + other];
    });
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
      for (const std::uint32_t end : index.ends(region[r])) {
        const std::uint32_t o = PairIndex::variable(end);
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
    return index.any_term(v, [&](std::uint32_t end, const PairIndex::Values& w) {
      return w[1] + w[2] > w[0] + w[3] && x[PairIndex::variable(end)] != x[v];
    });
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
    const std::span<const std::uint32_t> ends = index.ends(v);
    return std::any_of(ends.begin(), ends.end(), [&](std::uint32_t end) {
      const std::uint32_t o = PairIndex::variable(end);
      return open[o] != 0 && slab[o] != slab[v];
    });
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
