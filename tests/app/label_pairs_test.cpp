// SPDX-License-Identifier: MIT
// A tile result's pair list: what goes in comes out, in the bytes a version 08 result file
// holds (each field a zigzag varint delta), and damaged bytes are refused.
#include "label_pairs.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <vector>

#include "citymesh/core/varint.h"

namespace citymesh::app {
namespace {

std::vector<LabelPair> any_pairs(std::size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::vector<LabelPair> out;
  for (std::size_t k = 0; k < n; ++k) {
    const auto any = [&] {
      return k % 7 == 3 ? UINT32_MAX : static_cast<std::uint32_t>(rng() % (k % 2 ? 50 : UINT32_MAX));
    };
    out.push_back({any(), any(), k % 5 == 1 ? 0 : any(), any()});
  }
  return out;
}

LabelPairList list_of(const std::vector<LabelPair>& pairs) {
  LabelPairList list;
  for (const LabelPair& p : pairs) list.push_back(p);
  return list;
}

TEST(LabelPairList, GivesBackWhatWasAddedInTheResultFilesBytes) {
  const std::vector<LabelPair> pairs = any_pairs(5'000, 1);
  const LabelPairList list = list_of(pairs);
  EXPECT_EQ(list.size(), pairs.size());
  EXPECT_EQ(list.decoded(), pairs);
  // The bytes of encode_deltas before the list: VarintWriter::put_next field by field.
  VarintWriter w(pairs.size() * 4 * max_varint_bytes(32));
  LabelPair running{};
  for (const LabelPair& p : pairs) {
    for (const auto field :
         {&LabelPair::a_acquisition, &LabelPair::a_index, &LabelPair::b_acquisition, &LabelPair::b_index}) {
      w.put_next(p.*field, running.*field);
    }
  }
  EXPECT_EQ(list.bytes(), w.bytes());
  std::size_t counted = 0;
  LabelPair previous{};
  for (const LabelPair& p : pairs) {
    counted += LabelPairList::bytes_after(previous, p);
    previous = p;
  }
  EXPECT_EQ(counted, list.bytes().size());
}

TEST(LabelPairList, FromBytesTakesExactlyTheCountItWasWrittenWith) {
  const std::vector<LabelPair> pairs = any_pairs(300, 2);
  const LabelPairList list = list_of(pairs);
  const std::string bytes(list.bytes());
  const std::optional<LabelPairList> back = LabelPairList::from_bytes(bytes, pairs.size());
  ASSERT_TRUE(back.has_value());
  EXPECT_EQ(back->decoded(), pairs);
  // Adding after reading continues the deltas where the bytes ended.
  LabelPairList more = *back;
  more.push_back({1, 2, 3, 4});
  std::vector<LabelPair> longer = pairs;
  longer.push_back({1, 2, 3, 4});
  EXPECT_EQ(more.decoded(), longer);

  EXPECT_FALSE(LabelPairList::from_bytes(bytes, pairs.size() - 1));  // bytes left over
  EXPECT_FALSE(LabelPairList::from_bytes(bytes, pairs.size() + 1));  // runs out
  EXPECT_FALSE(LabelPairList::from_bytes(bytes.substr(0, bytes.size() - 1), pairs.size()));
  std::string unended = bytes;
  unended.back() = static_cast<char>(0x80);  // a varint that never ends
  EXPECT_FALSE(LabelPairList::from_bytes(unended, pairs.size()));
  EXPECT_TRUE(LabelPairList::from_bytes("", 0).has_value());
}

}  // namespace
}  // namespace citymesh::app
