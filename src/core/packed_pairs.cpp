// SPDX-License-Identifier: MIT
#include "citymesh/core/packed_pairs.h"

#include <algorithm>
#include <span>
#include <string>

#include "citymesh/core/parallel.h"
#include "citymesh/core/radix_sort.h"
#include "citymesh/core/varint.h"

namespace citymesh {

namespace {

/// One block's pairs (sorted) as PackedPairs lays them out, appended to `out`.
void pack_block(std::span<const PackedPairs::Pair> pairs, std::string& out) {
  std::uint32_t first = 0, run_second = 0;
  for (std::size_t k = 0; k < pairs.size();) {
    std::size_t end = k + 1;
    while (end < pairs.size() && pairs[end].first == pairs[k].first) ++end;
    append_varint(out, pairs[k].first - first);
    append_varint(out, static_cast<std::uint32_t>(end - k - 1));
    const std::uint32_t d = pairs[k].second - run_second;  // modulo 2^32, read as signed
    append_varint(out, d << 1 ^ static_cast<std::uint32_t>(static_cast<std::int32_t>(d) >> 31));
    for (std::size_t j = k + 1; j < end; ++j) append_varint(out, pairs[j].second - pairs[j - 1].second);
    first = pairs[k].first;
    run_second = pairs[k].second;
    k = end;
  }
}

}  // namespace

PackedPairs::PackedPairs(std::vector<Pair> pairs) : size_(pairs.size()) {
  if (!std::is_sorted(pairs.begin(), pairs.end())) radix_sort_pairs(pairs);
  const std::size_t blocks = (pairs.size() + kBlock - 1) / kBlock;
  // Blocks packed in parallel by chunks (fixed by the size alone: the same bytes on any
  // thread count), then laid end to end.
  constexpr std::size_t kBlocksPerChunk = 16;
  std::vector<std::string> chunks((blocks + kBlocksPerChunk - 1) / kBlocksPerChunk);
  block_at_.resize(blocks);
  block_first_.resize(blocks);
  parallel_for_blocks(blocks, kBlocksPerChunk, [&](std::size_t begin, std::size_t end) {
    std::string& out = chunks[begin / kBlocksPerChunk];
    for (std::size_t b = begin; b < end; ++b) {
      const std::size_t from = b * kBlock, to = std::min(from + kBlock, pairs.size());
      block_at_[b] = out.size();  // within the chunk for now
      block_first_[b] = pairs[from].first;
      pack_block(std::span(pairs).subspan(from, to - from), out);
    }
  });
  std::size_t total = 0;
  for (const std::string& c : chunks) total += c.size();
  bytes_.reserve(total);
  for (std::size_t c = 0; c < chunks.size(); ++c) {
    const std::uint64_t base = bytes_.size();
    for (std::size_t b = c * kBlocksPerChunk; b < std::min(blocks, (c + 1) * kBlocksPerChunk); ++b) {
      block_at_[b] += base;
    }
    bytes_.insert(bytes_.end(), chunks[c].begin(), chunks[c].end());
    std::string().swap(chunks[c]);
  }
}

PackedPairs::Iterator PackedPairs::block_begin(std::size_t block) const {
  if (block >= block_count()) return end();
  return {RunReader(bytes_.data() + block_at_[block]), block * kBlock, size_};
}

PackedPairs::Iterator PackedPairs::lower_bound(std::uint32_t first) const {
  // The last block starting below `first` may hold the answer; any later block starts at or
  // past it.
  const auto later = std::lower_bound(block_first_.begin(), block_first_.end(), first);
  const std::size_t block =
      later == block_first_.begin() ? 0 : static_cast<std::size_t>(later - block_first_.begin()) - 1;
  Iterator it = block_begin(block);
  while (it != end() && it->first < first) ++it;
  return it;
}

}  // namespace citymesh
