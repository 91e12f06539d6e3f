// SPDX-License-Identifier: MIT
#include "citymesh/core/radix_sort.h"

#include <algorithm>
#include <array>
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

/// Stable LSD radix sort on the bits of key_of() from `lowest_bit` up.
void sort_from_bit(std::span<Pair> values, unsigned lowest_bit) {
  if (values.size() < 2) return;
  std::uint64_t used = 0;  // the bits set in some key: digits outside it are all zero
  for (const Pair& p : values) used |= key_of(p);
  std::vector<Pair> buffer(values.size());
  std::span<Pair> from = values, to = buffer;
  for (unsigned shift = lowest_bit; shift < 64; shift += kDigitBits) {
    if (((used >> shift) & (kDigits - 1)) == 0) continue;
    counting_pass(from, to, shift);
    std::swap(from, to);
  }
  if (from.data() != values.data()) std::copy(from.begin(), from.end(), values.begin());
}

}  // namespace

void radix_sort_pairs(std::span<Pair> values) { sort_from_bit(values, 0); }

void stable_radix_sort_by_first(std::span<Pair> values) { sort_from_bit(values, 32); }

}  // namespace citymesh
