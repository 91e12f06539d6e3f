// SPDX-License-Identifier: MIT
#include <fmt/format.h>
#include <gtest/gtest.h>

#include "citymesh/core/atomic_file.h"
#include "citymesh/core/error.h"
#include "ended_process.h"
#include "test_support.h"

namespace citymesh {
namespace {

std::size_t files_in(const std::filesystem::path& dir) {
  return static_cast<std::size_t>(std::distance(std::filesystem::directory_iterator(dir), {}));
}

TEST(AtomicFile, CommitReplacesTheFinalFileWhole) {
  test::TempDir dir;
  const auto path = dir / "result.txt";
  test::write_text(path, "old");
  {
    AtomicFile file(path);
    file.write("new ");
    EXPECT_EQ(test::read_text(path), "old");  // unchanged until commit
    file.write("content");
    file.commit();
  }
  EXPECT_EQ(test::read_text(path), "new content");
  EXPECT_EQ(files_in(dir.path()), 1u);  // no temporary left behind
}

TEST(AtomicFile, AbandonedWriteLeavesNoFileAndNoTemporary) {
  test::TempDir dir;
  const auto path = dir / "never.txt";
  {
    AtomicFile file(path);
    file.write("half");
  }
  EXPECT_FALSE(std::filesystem::exists(path));
  EXPECT_EQ(files_in(dir.path()), 0u);
}

TEST(AtomicFile, CreatesParentFoldersAndReportsUnwritablePaths) {
  test::TempDir dir;
  write_file_atomically(dir / "a" / "b" / "c.txt", "x");
  EXPECT_EQ(test::read_text(dir / "a" / "b" / "c.txt"), "x");
  test::write_text(dir / "plain", "file");
  try {
    write_file_atomically(dir / "plain" / "child.txt", "x");  // parent is a file
    FAIL() << "expected OutputError";
  } catch (const OutputError& e) {
    EXPECT_NE(std::string(e.what()).find("child.txt"), std::string::npos);
    EXPECT_EQ(e.exit_code(), ExitCode::output);
  }
}

TEST(ProcessTag, NamesEndedProcessesOfThisMachineOnly) {
  const std::string host = test::host_name();
  const pid_t ended = test::ended_process();
  EXPECT_TRUE(tag_of_ended_local_process(fmt::format("{}.{}", host, ended)));
  EXPECT_FALSE(tag_of_ended_local_process(process_tag())) << "this process runs";
  EXPECT_FALSE(tag_of_ended_local_process(fmt::format("{}.{}", host, ::getppid()))) << "the parent runs";
  EXPECT_FALSE(tag_of_ended_local_process(fmt::format("other-{}.{}", host, ended))) << "another machine";
  EXPECT_FALSE(tag_of_ended_local_process(fmt::format("{}.x{}", host, ended)));
  EXPECT_FALSE(tag_of_ended_local_process(fmt::format("{}.", host)));
  EXPECT_FALSE(tag_of_ended_local_process(fmt::format("{}.0", host)));
  EXPECT_FALSE(tag_of_ended_local_process(fmt::format("{}.123456789012", host)));
  EXPECT_FALSE(tag_of_ended_local_process(""));
}

}  // namespace
}  // namespace citymesh
