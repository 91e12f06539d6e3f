// SPDX-License-Identifier: MIT
// A tile result's pairs, held as its file holds them.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "citymesh/core/decoding_iterator.h"

namespace citymesh::app {

/// A consistent pair (or pair of layers of one pass) with at least one owned member, as
/// (acquisition, index) twice.
struct LabelPair {
  std::uint32_t a_acquisition = 0, a_index = 0, b_acquisition = 0, b_index = 0;
  friend bool operator==(const LabelPair&, const LabelPair&) = default;
};

/// Pairs in the order they were added, each as its four fields' zigzag varint deltas against
/// the pair before: the bytes of a tile result's pair section. About 6 bytes a pair instead
/// of 16 when they come sorted: a spinning scanner's tile holds 45 M of them, which as plain
/// pairs took its end past the memory budget.
class LabelPairList {
 public:
  /// About what a sorted list takes per pair (6.2 bytes on a spinning scanner's tile).
  static constexpr std::size_t kBytesPerPair = 6;

  /// Reads the pairs from their bytes, checked by from_bytes or written by push_back.
  class DeltaReader {
   public:
    DeltaReader() = default;
    explicit DeltaReader(const char* at) : at_(at) {}
    void read(LabelPair& pair, std::size_t k);

   private:
    const char* at_ = nullptr;
  };
  /// Reads the pairs in order.
  using Iterator = DecodingIterator<LabelPair, DeltaReader>;

  LabelPairList() = default;
  /// The bytes of `count` pairs as bytes() gave them; nothing unless they hold exactly that.
  static std::optional<LabelPairList> from_bytes(std::string bytes, std::size_t count);

  /// The bytes `p` takes when added after `previous`.
  static std::size_t bytes_after(const LabelPair& previous, const LabelPair& p);
  /// Makes room for `bytes` bytes of pairs (bytes_after summed), so that adding them
  /// allocates nothing more.
  void reserve(std::size_t bytes) { bytes_.reserve(bytes); }
  void push_back(const LabelPair& p);

  [[nodiscard]] std::size_t size() const { return size_; }
  [[nodiscard]] bool empty() const { return size_ == 0; }
  [[nodiscard]] std::string_view bytes() const { return bytes_; }
  [[nodiscard]] Iterator begin() const { return {DeltaReader(bytes_.data()), 0, size_}; }
  [[nodiscard]] Iterator end() const { return {DeltaReader(), size_, size_}; }
  [[nodiscard]] std::vector<LabelPair> decoded() const { return {begin(), end()}; }

 private:
  std::string bytes_;
  std::size_t size_ = 0;
  LabelPair last_{};  ///< the pair the next one is a delta against
};

}  // namespace citymesh::app
