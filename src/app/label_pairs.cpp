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

}  // namespace

void LabelPairList::DeltaReader::read(LabelPair& pair, std::size_t /*k*/) {
  for (const auto field : kFields) {
    pair.*field =
        static_cast<std::uint32_t>(std::uint64_t{pair.*field} + unzigzag(read_trusted_varint<std::uint64_t>(at_)));
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
  for (const auto field : kFields) n += varint_size(stored(p.*field, previous.*field));
  return n;
}

void LabelPairList::push_back(const LabelPair& p) {
  for (const auto field : kFields) append_varint(bytes_, stored(p.*field, last_.*field));
  last_ = p;
  ++size_;
}

}  // namespace citymesh::app
