// SPDX-License-Identifier: MIT
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <random>
#include <string>

#include "citymesh/core/error.h"
#include "citymesh/core/read_file.h"
#include "test_support.h"

namespace citymesh {
namespace {

TEST(ReadFileBytes, ReturnsEveryByteOfSmallAndLargeFiles) {
  test::TempDir dir;
  std::mt19937 rng(7);
  for (const std::size_t size : {std::size_t{0}, std::size_t{1}, std::size_t{65536}, std::size_t{1'000'003}}) {
    std::string bytes(size, '\0');
    for (char& c : bytes) c = static_cast<char>(rng() & 0xff);
    const auto file = dir.path() / fmt::format("f{}", size);
    test::write_text(file, bytes);
    const std::optional<std::string> read = read_file_bytes(file);
    ASSERT_TRUE(read.has_value());
    EXPECT_EQ(*read, bytes) << size;
  }
}

TEST(ReadFileBytes, MissingFilesAndFoldersAreNotOpened) {
  test::TempDir dir;
  EXPECT_FALSE(read_file_bytes(dir.path() / "missing.bin").has_value());
  EXPECT_FALSE(read_file_bytes(dir.path()).has_value());
}

TEST(ReadFileRanges, ConcatenatesRangesInTheOrderAsked) {
  test::TempDir dir;
  std::string bytes(100'000, '\0');
  std::mt19937 rng(3);
  for (char& c : bytes) c = static_cast<char>(rng() & 0xff);
  const auto file = dir.path() / "blocks.bin";
  test::write_text(file, bytes);
  const std::vector<ByteRange> ranges{{90'000, 10'000}, {0, 7}, {500, 0}, {12'345, 54'321}};
  std::string expected;
  for (const ByteRange& r : ranges) expected += bytes.substr(r.offset, r.bytes);
  EXPECT_EQ(read_file_ranges(file, ranges, "test"), expected);
  EXPECT_EQ(read_file_ranges(file, {}, "test"), "");
}

TEST(ReadFileRanges, ARangePastTheEndOrAMissingFileIsAnInputErrorNamingTheSource) {
  test::TempDir dir;
  const auto file = dir.path() / "blocks.bin";
  test::write_text(file, std::string(1000, 'x'));
  const auto expect_error = [&](const std::filesystem::path& f, const std::vector<ByteRange>& ranges) {
    try {
      (void)read_file_ranges(f, ranges, "the source");
      FAIL() << "no error";
    } catch (const InputError& e) {
      EXPECT_EQ(std::string(e.what()).rfind("the source: ", 0), 0u) << e.what();
    }
  };
  expect_error(file, {{0, 10}, {995, 6}});
  expect_error(file, {{1001, 0}});
  expect_error(file, {{10, ~std::uint64_t{0}}});  // no allocation of that size is attempted
  expect_error(dir.path() / "missing.bin", {{0, 1}});
}

}  // namespace
}  // namespace citymesh
