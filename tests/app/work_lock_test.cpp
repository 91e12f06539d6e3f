// SPDX-License-Identifier: MIT
// One full run at a time in a work folder; the subsets of one run share it.
#include "work_lock.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <optional>
#include <string>

#include "citymesh/core/atomic_file.h"
#include "citymesh/core/error.h"
#include "test_support.h"

namespace citymesh::app {
namespace {

/// The message of the OutputError that taking the lock throws, or "" when it is taken.
std::string refusal(const std::filesystem::path& work, bool exclusive) {
  try {
    const WorkFolderLock lock(work, exclusive);
    return "";
  } catch (const OutputError& e) {
    return e.what();
  }
}

TEST(WorkFolderLock, AFullRunExcludesEveryOtherRunAndSubsetsShare) {
  test::TempDir tmp;
  const std::filesystem::path work = tmp / "work";
  {
    const WorkFolderLock full(work, true);
    const std::string message = refusal(work, true);
    EXPECT_NE(message.find(work.string() + ": the work folder is in use by another citymesh run"), std::string::npos)
        << message;
    EXPECT_NE(message.find(process_tag()), std::string::npos) << "names the holder: " << message;
    EXPECT_FALSE(refusal(work, false).empty()) << "a subset waits for the full run too";
  }
  EXPECT_EQ(refusal(work, true), "") << "released with its holder";
  {
    const WorkFolderLock subset(work, false);
    EXPECT_EQ(refusal(work, false), "") << "another subset of the run";
    EXPECT_FALSE(refusal(work, true).empty()) << "a full run while subsets work";
  }
  EXPECT_EQ(refusal(work, true), "");
}

TEST(WorkFolderLock, ARunRefusesAWorkFolderInUseAndRunsOnceItIsFree) {
  test::TempDir dir;
  const std::string sim = (dir / "sim").string();
  ASSERT_EQ(test::run_citymesh(fmt::format("simulate --out {} --length 30", sim)).exit_code, 0);
  const std::string run = fmt::format("run {}/config.toml --no-pictures", sim);
  std::optional<WorkFolderLock> other(std::in_place, dir / "sim/work", true);
  const auto refused = test::run_citymesh(run);
  EXPECT_EQ(refused.exit_code, static_cast<int>(ExitCode::output)) << refused.err;
  EXPECT_NE(refused.err.find("in use by another citymesh run"), std::string::npos) << refused.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "sim/out")) << "nothing written";
  other.reset();
  const auto done = test::run_citymesh(run);
  EXPECT_EQ(done.exit_code, 0) << done.err;
}

}  // namespace
}  // namespace citymesh::app
