// SPDX-License-Identifier: MIT
#include "citymesh/core/varint.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <string>
#include <vector>

namespace citymesh {
namespace {

/// LEB128 as the format defines it, written independently of VarintWriter: the oracle for
/// its bytes.
std::string leb128(std::uint64_t v) {
  std::string out;
  do {
    const auto low = static_cast<char>(v & 0x7f);
    v >>= 7;
    out += static_cast<char>(low | (v != 0 ? 0x80 : 0));
  } while (v != 0);
  return out;
}

/// Values of every bit width from 0 to 64, each width's extremes and random values between.
std::vector<std::uint64_t> values_of_every_width(std::mt19937_64& rng) {
  std::vector<std::uint64_t> values{0};
  for (unsigned bits = 1; bits <= 64; ++bits) {
    const std::uint64_t low = std::uint64_t{1} << (bits - 1), high = low | (low - 1);
    values.push_back(low);
    values.push_back(high);
    for (int k = 0; k < 20; ++k) values.push_back(low | (rng() & (low - 1)));
  }
  std::shuffle(values.begin(), values.end(), rng);
  return values;
}

TEST(Varint, WriterGivesTheBytesOfLeb128ForEveryWidth) {
  std::mt19937_64 rng(11);
  const std::vector<std::uint64_t> values = values_of_every_width(rng);
  std::string expected;
  for (const std::uint64_t v : values) expected += leb128(v);
  // Room for exactly these bytes: the sanitizer build checks that no write goes past it.
  VarintWriter w(expected.size());
  for (const std::uint64_t v : values) w.put(v);
  EXPECT_EQ(std::string(w.bytes()), expected);

  VarintReader r(w.bytes().data(), w.bytes().data() + w.bytes().size());
  for (const std::uint64_t v : values) {
    std::uint64_t back = 0;
    ASSERT_TRUE(r.get(back));
    EXPECT_EQ(back, v);
  }
  EXPECT_TRUE(r.at_end());
}

TEST(Varint, DeltasRoundTripAndSmallStepsTakeOneByte) {
  std::mt19937_64 rng(5);
  std::vector<std::uint32_t> sequence;
  std::uint32_t x = 4000000000u;
  for (int k = 0; k < 5000; ++k) sequence.push_back(x += static_cast<std::uint32_t>(rng() % 127) - 63);
  for (int k = 0; k < 100; ++k) sequence.push_back(static_cast<std::uint32_t>(rng()));  // any jump, wrapping
  VarintWriter w(sequence.size() * max_varint_bytes(32));
  std::uint32_t running = 0;
  for (const std::uint32_t v : sequence) w.put_next(v, running);
  // Each small step (|d| <= 63 zigzags below 128) is one byte; the first value and the jumps
  // take at most five.
  EXPECT_LE(w.bytes().size(), 5000 - 1 + 5 * 101);

  VarintReader r(w.bytes().data(), w.bytes().data() + w.bytes().size());
  std::uint64_t back = 0;
  for (const std::uint32_t v : sequence) {
    ASSERT_TRUE(r.get_next(back));
    EXPECT_EQ(static_cast<std::uint32_t>(back), v);
  }
  EXPECT_TRUE(r.at_end());
}

TEST(Varint, ReaderRefusesTruncatedAndOverlongVarints) {
  const std::string truncated = leb128(std::uint64_t{1} << 40).substr(0, 3);
  VarintReader r(truncated.data(), truncated.data() + truncated.size());
  std::uint64_t v = 0;
  EXPECT_FALSE(r.get(v));
  const std::string eleven(11, static_cast<char>(0x80));
  VarintReader o(eleven.data(), eleven.data() + eleven.size());
  EXPECT_FALSE(o.get(v));
}

}  // namespace
}  // namespace citymesh
