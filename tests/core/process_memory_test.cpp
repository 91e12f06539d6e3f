// SPDX-License-Identifier: MIT
#include "citymesh/core/process_memory.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>

namespace citymesh {
namespace {

constexpr std::size_t kMiB = 1 << 20;

TEST(ProcessMemory, ReadsThisProcesssResidentSet) {
  const std::uint64_t now = resident_bytes();
  EXPECT_GT(now, 0u);
  EXPECT_GE(peak_resident_bytes(), now);
}

TEST(ProcessMemory, TheMachinesMemoryHoldsThisProcessAndAgreesWithProc) {
  const std::uint64_t machine = physical_memory_bytes();
  EXPECT_GT(machine, peak_resident_bytes());
  // /proc/meminfo's MemTotal is what the kernel manages: a little under the pages counted.
  std::ifstream meminfo("/proc/meminfo");
  std::string key;
  std::uint64_t kib = 0;
  ASSERT_TRUE(meminfo >> key >> kib);
  ASSERT_EQ(key, "MemTotal:");
  EXPECT_NEAR(static_cast<double>(machine), static_cast<double>(kib) * 1024, 0.05 * static_cast<double>(machine));
}

#if defined(__GLIBC__) && !defined(__SANITIZE_ADDRESS__)  // ASan has its own allocator
TEST(ProcessMemory, FreedMemoryStaysForReuse) {
  keep_freed_memory_for_reuse();
  // A block far above glibc's default mmap threshold: with the defaults it would be unmapped
  // on free and the resident set would drop by its size.
  constexpr std::size_t kBlock = 256 * kMiB;
  const std::uint64_t before = resident_bytes();
  auto* block = static_cast<char*>(std::malloc(kBlock));
  ASSERT_NE(block, nullptr);
  std::memset(block, 1, kBlock);  // faulted in
  const std::uint64_t touched = resident_bytes();
  EXPECT_GE(touched, before + kBlock / 2);
  std::free(block);
  EXPECT_GE(resident_bytes(), touched - 16 * kMiB) << "the freed block went back to the system";
  // And the next block of the same size reuses those pages.
  auto* again = static_cast<char*>(std::malloc(kBlock));
  ASSERT_NE(again, nullptr);
  std::memset(again, 2, kBlock);
  EXPECT_LE(resident_bytes(), touched + 16 * kMiB);
  std::free(again);
}

TEST(ProcessMemory, ReleasedMemoryLeavesTheResidentSet) {
  keep_freed_memory_for_reuse();
  constexpr std::size_t kBlock = 256 * kMiB;
  auto* block = static_cast<char*>(std::malloc(kBlock));
  ASSERT_NE(block, nullptr);
  std::memset(block, 1, kBlock);
  const std::uint64_t touched = resident_bytes();
  std::free(block);
  release_freed_memory();  // what a run does between its stages
  EXPECT_LE(resident_bytes(), touched - kBlock / 2) << "the freed block stayed resident";
}
#endif

}  // namespace
}  // namespace citymesh
