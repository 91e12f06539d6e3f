// SPDX-License-Identifier: MIT
#include "citymesh/core/record_file.h"

#include <gtest/gtest.h>

#include <fstream>

#include "citymesh/core/error.h"
#include "test_support.h"

namespace citymesh {
namespace {

void expect_input_error(const std::filesystem::path& p, std::string_view fragment) {
  try {
    (void)read_u32_records(p, "CMTEST01", "test records");
    FAIL() << "no error for " << p;
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(p.filename().string()), std::string::npos) << e.what();
  }
}

TEST(RecordFile, RoundTripsAndRejectsDamagedFiles) {
  test::TempDir dir;
  const std::vector<std::uint32_t> values{1, 2, 3, 0xFFFFFFFFu, 42};
  write_u32_records(dir / "ok.bin", "CMTEST01", values);
  EXPECT_EQ(read_u32_records(dir / "ok.bin", "CMTEST01", "test records"), values);
  const std::string bytes = test::read_text(dir / "ok.bin");

  expect_input_error(dir / "missing.bin", "cannot open");
  test::write_text(dir / "magic.bin", "CMOTHER1" + bytes.substr(8));
  expect_input_error(dir / "magic.bin", "not a citymesh test records file");
  test::write_text(dir / "short.bin", bytes.substr(0, bytes.size() - 3));
  expect_input_error(dir / "short.bin", "truncated");
  std::string flipped = bytes;
  flipped[20] = static_cast<char>(flipped[20] ^ 1);
  test::write_text(dir / "flipped.bin", flipped);
  expect_input_error(dir / "flipped.bin", "checksum");
  // A huge count in the header is caught before any allocation.
  std::string huge = bytes;
  for (int k = 8; k < 16; ++k) huge[static_cast<std::size_t>(k)] = static_cast<char>(0xff);
  test::write_text(dir / "huge.bin", huge);
  expect_input_error(dir / "huge.bin", "count");
}

TEST(RecordFile, WrittenInPartsEqualsWrittenWholeAndNothingBeforeCommit) {
  test::TempDir dir;
  const std::vector<std::uint32_t> values{7, 0, 0xFFFFFFFFu, 12, 99, 3, 5};
  write_u32_records(dir / "whole.bin", "CMTEST01", values);
  {
    U32RecordWriter parts(dir / "parts.bin", "CMTEST01");
    parts.add(std::span(values).first(2));
    parts.add({});
    parts.add(std::span(values).subspan(2));
    EXPECT_EQ(parts.count(), values.size());
    parts.commit();
  }
  EXPECT_EQ(test::read_text(dir / "parts.bin"), test::read_text(dir / "whole.bin"));
  {
    U32RecordWriter abandoned(dir / "abandoned.bin", "CMTEST01");
    abandoned.add(values);
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "abandoned.bin"));
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.path()), std::filesystem::directory_iterator{}), 2);
}

}  // namespace
}  // namespace citymesh
