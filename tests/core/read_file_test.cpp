// SPDX-License-Identifier: MIT
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <random>
#include <string>

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

}  // namespace
}  // namespace citymesh
