// SPDX-License-Identifier: MIT
#include "citymesh/core/radix_sort.h"

#include <algorithm>
#include <array>
#include <bit>
#include <vector>

namespace citymesh {

namespace {

using Pair = std::pair<std::uint32_t, std::uint32_t>;

constexpr unsigned kDigitBits = 11;
constexpr std::uint32_t kDigits = 1u << kDigitBits;

/// The 64-bit key whose numeric order is the pairs' lexicographic order.
std::uint64_t key_of(const Pair& p) { return (std::uint64_t{p.first} << 32) | p.second; }

/// One stable counting pass on the digit at `shift`, from `in` to `out`.
void counting_pass(std::span<const Pair> in, std::span<Pair> out, unsigned shift) {
  std::array<std::size_t, kDigits> start{};
  for (const Pair& p : in) ++start[(key_of(p) >> shift) & (kDigits - 1)];
  std::size_t sum = 0;
  for (std::size_t& s : start) {
    const std::size_t count = s;
    s = sum;
    sum += count;
  }
  for (const Pair& p : in) out[start[(key_of(p) >> shift) & (kDigits - 1)]++] = p;
}

/// Stable LSD radix sort on the bits of key_of() from `lowest_bit` up, through `buffer` (as
/// large as `values`). Digits on which every key agrees are skipped: a pass over them would
/// move nothing.
void sort_from_bit(std::span<Pair> values, unsigned lowest_bit, std::span<Pair> buffer) {
  if (values.size() < 2) return;
  std::uint64_t any = 0, all = ~std::uint64_t{0};
  for (const Pair& p : values) {
    any |= key_of(p);
    all &= key_of(p);
  }
  const std::uint64_t varying = any ^ all;
  std::span<Pair> from = values, to = buffer.first(values.size());
  for (unsigned shift = lowest_bit; shift < 64; shift += kDigitBits) {
    if (((varying >> shift) & (kDigits - 1)) == 0) continue;
    counting_pass(from, to, shift);
    std::swap(from, to);
  }
  if (from.data() != values.data()) std::copy(from.begin(), from.end(), values.begin());
}

void sort_from_bit(std::span<Pair> values, unsigned lowest_bit) {
  std::vector<Pair> buffer(values.size());
  sort_from_bit(values, lowest_bit, buffer);
}

/// From this many pairs on, radix_sort_pairs() first splits them in place by their highest
/// 8 bits in use (an American flag pass: no second array), then sorts each part through a
/// buffer of the largest part's size. A spinning scanner's tile sorts 47 M pairs (377 MB):
/// the buffer as large as them set the change step's peak.
constexpr std::size_t kSplitInPlaceFrom = std::size_t{1} << 20;
constexpr unsigned kSplitBits = 8;
constexpr std::size_t kParts = std::size_t{1} << kSplitBits;

/// Sorts by splitting in place first (see kSplitInPlaceFrom). Not stable: equal keys are
/// equal pairs.
void sort_split_in_place(std::span<Pair> values) {
  std::uint64_t any = 0;
  for (const Pair& p : values) any |= key_of(p);
  if (any == 0) return;
  const unsigned top = 63 - static_cast<unsigned>(std::countl_zero(any));
  const unsigned shift = top >= kSplitBits - 1 ? top - (kSplitBits - 1) : 0;
  const auto part = [&](const Pair& p) { return static_cast<std::size_t>(key_of(p) >> shift) & (kParts - 1); };
  std::array<std::size_t, kParts + 1> start{};
  for (const Pair& p : values) ++start[part(p) + 1];
  for (std::size_t b = 0; b < kParts; ++b) start[b + 1] += start[b];
  // Each pair out of place is carried to the next free slot of its part, and the pair found
  // there carried on, until one belongs where the walk began.
  std::array<std::size_t, kParts> next{};
  std::copy(start.begin(), start.end() - 1, next.begin());
  for (std::size_t b = 0; b < kParts; ++b) {
    while (next[b] < start[b + 1]) {
      Pair carried = values[next[b]];
      for (std::size_t d = part(carried); d != b; d = part(carried)) std::swap(carried, values[next[d]++]);
      values[next[b]++] = carried;
    }
  }
  std::size_t largest = 0;
  for (std::size_t b = 0; b < kParts; ++b) largest = std::max(largest, start[b + 1] - start[b]);
  std::vector<Pair> buffer(largest);
  for (std::size_t b = 0; b < kParts; ++b) sort_from_bit(values.subspan(start[b], start[b + 1] - start[b]), 0, buffer);
}

}  // namespace

void radix_sort_pairs(std::span<Pair> values) {
  if (values.size() >= kSplitInPlaceFrom) {
    sort_split_in_place(values);
  } else {
    sort_from_bit(values, 0);
  }
}

void stable_radix_sort_by_first(std::span<Pair> values) { sort_from_bit(values, 32); }

}  // namespace citymesh
