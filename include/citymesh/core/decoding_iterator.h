// SPDX-License-Identifier: MIT
// The iterator of lists held encoded (PackedPairs, a tile result's pairs): each value is
// decoded from the bytes when the iterator reaches it.
#pragma once

#include <cstddef>
#include <iterator>

namespace citymesh {

/// An input iterator over `size` values decoded one after another: `Decoder` holds where the
/// bytes are read and what the next value is a delta against, and `decoder.read(value, k)`
/// turns `value` (value k - 1, or a value-initialised one for k = 0) into value k. Two
/// iterators of one list are equal when they are at the same value.
template <class Value, class Decoder>
class DecodingIterator {
 public:
  using iterator_category = std::input_iterator_tag;
  using value_type = Value;
  using difference_type = std::ptrdiff_t;
  using reference = const Value&;
  using pointer = const Value*;

  DecodingIterator() = default;
  /// At value k of `size`, with `decoder` ready to read it.
  DecodingIterator(Decoder decoder, std::size_t k, std::size_t size) : decoder_(decoder), k_(k), size_(size) {
    if (k_ < size_) decoder_.read(value_, k_);
  }

  const Value& operator*() const { return value_; }
  const Value* operator->() const { return &value_; }
  DecodingIterator& operator++() {
    if (++k_ < size_) decoder_.read(value_, k_);
    return *this;
  }
  DecodingIterator operator++(int) {
    DecodingIterator before = *this;
    ++*this;
    return before;
  }
  /// Which value of the list this is (its size at the end).
  [[nodiscard]] std::size_t index() const { return k_; }
  friend bool operator==(const DecodingIterator& x, const DecodingIterator& y) { return x.k_ == y.k_; }

 private:
  Decoder decoder_{};
  std::size_t k_ = 0, size_ = 0;
  Value value_{};
};

}  // namespace citymesh
