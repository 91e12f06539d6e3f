// SPDX-License-Identifier: MIT
// The tiler's block file: gathered in pages, written in the background, with O_DIRECT where
// the file system takes it (the test folder) and through the page cache where it does not
// (tmpfs).
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "citymesh/core/error.h"
#include "citymesh/core/read_file.h"
#include "test_support.h"
#include "tile_block_writer.h"

namespace citymesh {
namespace {

using tiler_detail::BlockAppender;

/// Appends blocks of random sizes (a byte to 9 MiB: within a page, across pages and across
/// several 4 MiB gathers), each of up to three parts, and checks the file and every range.
void expect_blocks_read_back(const std::filesystem::path& file) {
  std::mt19937 rng(21);
  std::string expected;
  std::vector<ByteRange> ranges;
  std::vector<std::string> blocks;
  {
    BlockAppender appender(file);
    for (int b = 0; b < 40; ++b) {
      const std::size_t size = b % 7 == 0 ? rng() % (9u << 20) : 1 + rng() % 9000;
      std::string block(size, '\0');
      for (char& c : block) c = static_cast<char>(rng());
      const std::size_t cut1 = size / 3, cut2 = size / 2;
      const std::string_view v(block);
      ranges.push_back(appender.append({v.substr(0, cut1), v.substr(cut1, cut2 - cut1), v.substr(cut2)}));
      EXPECT_EQ(ranges.back().offset, expected.size());
      EXPECT_EQ(ranges.back().bytes, size);
      expected += block;
      blocks.push_back(std::move(block));
    }
    appender.close();
  }
  EXPECT_EQ(std::filesystem::file_size(file), expected.size());
  EXPECT_TRUE(read_file_bytes(file) == expected);
  for (std::size_t b = 0; b < blocks.size(); b += 5) {
    EXPECT_TRUE(read_file_ranges(file, std::span(&ranges[b], 1), "test") == blocks[b]) << b;
  }
}

TEST(BlockAppender, BlocksReadBackWithDirectWrites) {
  test::TempDir dir;
  expect_blocks_read_back(dir / "blocks.bin");
}

TEST(BlockAppender, BlocksReadBackThroughThePageCacheOnTmpfs) {
  // tmpfs refuses O_DIRECT: the appender falls back to buffered writes.
  const std::filesystem::path shm = "/dev/shm";
  if (!std::filesystem::is_directory(shm)) GTEST_SKIP() << "no /dev/shm";
  const std::filesystem::path file = shm / ("citymesh_block_appender_test." + std::to_string(::getpid()));
  expect_blocks_read_back(file);
  std::filesystem::remove(file);
}

TEST(BlockAppender, AnEmptyFileStaysEmpty) {
  test::TempDir dir;
  BlockAppender appender(dir / "blocks.bin");
  appender.close();
  EXPECT_EQ(std::filesystem::file_size(dir / "blocks.bin"), 0u);
}

TEST(BlockAppender, AFileThatCannotBeCreatedIsAnOutputErrorNamingIt) {
  test::TempDir dir;
  try {
    BlockAppender appender(dir / "missing" / "blocks.bin");
    FAIL() << "no error";
  } catch (const OutputError& e) {
    EXPECT_NE(std::string(e.what()).find((dir / "missing" / "blocks.bin").string()), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace citymesh
