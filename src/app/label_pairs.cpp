// SPDX-License-Identifier: MIT
#include "label_pairs.h"

#include <array>

#include "citymesh/core/varint.h"

namespace citymesh::app {

namespace {

/// The fields in the order they are stored.
constexpr std::array kFields{&LabelPair::a_acquisition, &LabelPair::a_index, &LabelPair::b_acquisition,
                             &LabelPair::b_index};

/// A field as stored: the zigzag of its difference from the previous pair's (VarintWriter's
/// put_next on 32-bit values).
std::uint64_t stored(std::uint32_t value, std::uint32_t previous) {
  return zigzag(std::uint64_t{value} - std::uint64_t{previous});
}

std::size_t varint_bytes(std::uint64_t v) {
  std::size_t n = 1;
  for (; v >= 0x80; v >>= 7) ++n;
  return n;
}

/// A varint of bytes known good (checked by from_bytes or written by push_back).
std::uint64_t read_varint(const char*& at) {
  std::uint64_t v = 0;
  for (unsigned shift = 0;; shift += 7) {
    const auto byte = static_cast<std::uint8_t>(*at++);
    v |= std::uint64_t{byte & 0x7fu} << shift;
    if (byte < 0x80) return v;
  }
}

}  // namespace

void LabelPairList::DeltaReader::read(LabelPair& pair, std::size_t /*k*/) {
  for (const auto field : kFields) {
    pair.*field = static_cast<std::uint32_t>(std::uint64_t{pair.*field} + unzigzag(read_varint(at_)));
  }
}

std::optional<LabelPairList> LabelPairList::from_bytes(std::string bytes, std::size_t count) {
  VarintReader in(bytes.data(), bytes.data() + bytes.size());
  LabelPair running{};
  for (std::size_t k = 0; k < count; ++k) {
    for (const auto field : kFields) {
      if (!in.get_next(running.*field)) return std::nullopt;
    }
  }
  if (!in.at_end()) return std::nullopt;
  LabelPairList list;
  list.bytes_ = std::move(bytes);
  list.size_ = count;
  list.last_ = running;
  return list;
}

std::size_t LabelPairList::bytes_after(const LabelPair& previous, const LabelPair& p) {
  std::size_t n = 0;
  for (const auto field : kFields) n += varint_bytes(stored(p.*field, previous.*field));
  return n;
}

void LabelPairList::push_back(const LabelPair& p) {
  for (const auto field : kFields) {
    for (std::uint64_t v = stored(p.*field, last_.*field);; v >>= 7) {
      if (v < 0x80) {
        bytes_.push_back(static_cast<char>(v));
        break;
      }
      bytes_.push_back(static_cast<char>(v | 0x80));
    }
  }
  last_ = p;
  ++size_;
}

}  // namespace citymesh::app
