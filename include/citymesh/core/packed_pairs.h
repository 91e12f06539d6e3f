// SPDX-License-Identifier: MIT
// A sorted list of pairs of 32-bit ids held packed. The change step's consistent pairs and
// pairs of layers run to tens of millions on a spinning scanner's tile (47 M and 9 M on the
// largest tile of a 30 m street: 450 MB as plain pairs, 132 MB packed), and the mosaic holds
// them while it solves, beside its own terms.
#pragma once

#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <utility>
#include <vector>

#include "citymesh/core/decoding_iterator.h"
#include "citymesh/core/varint.h"

namespace citymesh {

/// Pairs sorted by (first, second), stored as runs of one `first`: per run, its `first` as a
/// varint delta from the previous run's, its length less one, its first `second` as a zigzag
/// varint delta from the previous run's first `second`, then each further `second` as a
/// delta from the one before (a spinning street's pairs: 2.3 bytes each). Every kBlock pairs
/// a block starts afresh, so that a block reads on its own: blocks in parallel, and
/// lower_bound by bisection over the blocks' first ids. Immutable once made.
class PackedPairs {
 public:
  using Pair = std::pair<std::uint32_t, std::uint32_t>;
  static constexpr std::size_t kBlock = 4096;

  /// Reads one block's runs (see the class comment).
  class RunReader {
   public:
    RunReader() = default;
    explicit RunReader(const std::uint8_t* at) : at_(at) {}
    void read(Pair& pair, std::size_t k) {
      if (left_in_run_ > 0) {
        --left_in_run_;
        pair.second += read_trusted_varint<std::uint32_t>(at_);
        return;
      }
      if (k % kBlock == 0) pair.first = run_second_ = 0;  // a block starts afresh
      pair.first += read_trusted_varint<std::uint32_t>(at_);
      left_in_run_ = read_trusted_varint<std::uint32_t>(at_);
      const auto z = read_trusted_varint<std::uint32_t>(at_);
      run_second_ += (z >> 1) ^ (0u - (z & 1u));
      pair.second = run_second_;
    }

   private:
    const std::uint8_t* at_ = nullptr;
    std::uint32_t left_in_run_ = 0;  ///< pairs of the current run still to come
    std::uint32_t run_second_ = 0;   ///< the current run's first `second`
  };
  /// Reads the pairs in order.
  using Iterator = DecodingIterator<Pair, RunReader>;

  PackedPairs() = default;
  /// Packs `pairs`, sorting them first when they come unsorted (duplicates stay). Implicit:
  /// a list made as a vector is assigned as it is.
  PackedPairs(std::vector<Pair> pairs);  // NOLINT(google-explicit-constructor)
  PackedPairs(std::initializer_list<Pair> pairs) : PackedPairs(std::vector<Pair>(pairs)) {}

  [[nodiscard]] std::size_t size() const { return size_; }
  [[nodiscard]] bool empty() const { return size_ == 0; }
  [[nodiscard]] Iterator begin() const { return block_begin(0); }
  [[nodiscard]] Iterator end() const { return {RunReader(), size_, size_}; }

  /// Blocks of kBlock pairs (the last one shorter); block_begin(block_count()) is end().
  [[nodiscard]] std::size_t block_count() const { return block_at_.size(); }
  [[nodiscard]] Iterator block_begin(std::size_t block) const;

  /// The first pair whose `first` is at least `first`.
  [[nodiscard]] Iterator lower_bound(std::uint32_t first) const;

  /// The pairs as a plain list.
  [[nodiscard]] std::vector<Pair> unpacked() const { return {begin(), end()}; }
  /// The bytes held.
  [[nodiscard]] std::size_t bytes() const {
    return bytes_.capacity() + block_at_.capacity() * sizeof(std::uint64_t) +
           block_first_.capacity() * sizeof(std::uint32_t);
  }

  friend bool operator==(const PackedPairs& x, const PackedPairs& y) {
    return x.size_ == y.size_ && x.bytes_ == y.bytes_;
  }

 private:
  std::vector<std::uint8_t> bytes_;
  std::vector<std::uint64_t> block_at_;     ///< where each block starts in bytes_
  std::vector<std::uint32_t> block_first_;  ///< each block's first `first`
  std::size_t size_ = 0;
};

}  // namespace citymesh
