// SPDX-License-Identifier: MIT
// What killed runs leave behind is removed when the next run starts, and nothing else is.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <fstream>

#include "citymesh/core/atomic_file.h"
#include "ended_process.h"
#include "leftovers.h"
#include "test_support.h"

namespace citymesh::app {
namespace {

void touch(const std::filesystem::path& path) {
  std::filesystem::create_directories(path.parent_path());
  std::ofstream(path) << "x";
}

TEST(Leftovers, TagsAreFoundInTheNamesRunsGiveTheirOwnFiles) {
  EXPECT_EQ(process_tag_in_name("0_1.bin.tmp.vm.42", "results"), "vm.42");
  EXPECT_EQ(process_tag_in_name("run.json.tmp.host.example.org.7", "out"), "host.example.org.7");
  EXPECT_EQ(process_tag_in_name("pairs.vm.42", "work"), "vm.42");
  EXPECT_EQ(process_tag_in_name("seams.vm.42", "work"), "vm.42");
  EXPECT_EQ(process_tag_in_name("a12.vm.42", "staging"), "vm.42");
  EXPECT_EQ(process_tag_in_name("a12.vm.42", "tiles"), "");  // only the tiler's staging folders
  EXPECT_EQ(process_tag_in_name("ab.vm.42", "staging"), "");
  EXPECT_EQ(process_tag_in_name("0_1.bin", "results"), "");
  EXPECT_EQ(process_tag_in_name("acq_0.ply", "sim"), "");
  EXPECT_EQ(process_tag_in_name(".tmp.vm.42", "out"), "");
}

TEST(Leftovers, OnlyWhatEndedProcessesOfThisMachineLeftIsRemoved) {
  test::TempDir dir;
  const std::string host = test::host_name();
  const std::string ended = fmt::format("{}.{}", host, test::ended_process());
  const std::string running = process_tag();
  const std::string elsewhere = fmt::format("other-{}", ended);
  const std::vector<std::filesystem::path> gone{
      dir / ("work/pairs." + ended + "/range0.bin"),
      dir / ("work/seams." + ended + "/0_1_1.input.part"),
      dir / ("work/results/0_1.bin.tmp." + ended),
      dir / ("work/tiles/staging/a3." + ended + "/0_0.bin"),
      dir / ("out/mosaic/mosaic.ply.tmp." + ended),
  };
  const std::vector<std::filesystem::path> kept{
      dir / ("work/pairs." + running + "/range0.bin"),
      dir / ("work/seams." + running + "/0_1_1.input.part"),
      dir / ("work/pairs." + elsewhere + "/range0.bin"),
      dir / ("work/results/0_2.bin.tmp." + running),
      dir / ("work/results/0_3.bin.tmp." + elsewhere),
      dir / "work/results/0_1.bin",
      dir / "work/tiles/a3/0_0.bin",
      dir / ("work/tiles/a3/notes." + ended),
  };
  for (const auto& p : gone) touch(p);
  for (const auto& p : kept) touch(p);

  EXPECT_EQ(remove_leftovers_of_ended_runs(dir.path()), gone.size());
  for (const auto& p : gone) EXPECT_FALSE(std::filesystem::exists(p)) << p;
  EXPECT_FALSE(std::filesystem::exists(dir / ("work/pairs." + ended))) << "the folder goes whole";
  EXPECT_FALSE(std::filesystem::exists(dir / ("work/tiles/staging/a3." + ended)));
  for (const auto& p : kept) EXPECT_TRUE(std::filesystem::exists(p)) << p;
  EXPECT_EQ(remove_leftovers_of_ended_runs(dir.path()), 0u);
  EXPECT_EQ(remove_leftovers_of_ended_runs(dir / "missing"), 0u);
}

}  // namespace
}  // namespace citymesh::app
