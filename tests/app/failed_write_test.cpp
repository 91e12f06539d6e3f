// SPDX-License-Identifier: MIT
// What a run does when a write fails (a full disk, a quota, a file size limit): it stops with
// exit code 4 and a message naming the file and the system's reason, and the same command run
// again once there is room finishes with the bytes of a run that never failed. The failures
// come from a file size limit (RLIMIT_FSIZE, with SIGXFSZ ignored: a write past it fails with
// EFBIG, as one on a full disk fails with ENOSPC), set at sizes taken from an unbroken run's
// own files so that each stops a later stage.
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "test_support.h"

namespace citymesh {
namespace {

/// `run` of the simulated street in tiles of 10 m, into output `name` and work folder
/// `work-<name>`, with `extra` options.
std::string tiled_run_args(const std::filesystem::path& sim, const std::string& name, const std::string& extra = "") {
  return fmt::format(
      "run {}/config.toml --no-pictures --threads 2 --set tiling.tile_size=10 --set project.output={} "
      "--set project.work=work-{} {}",
      sim.string(), name, name, extra);
}

/// The sizes of the files under `folder` whose name holds `part`.
std::vector<std::uintmax_t> file_sizes(const std::filesystem::path& folder, const std::string& part) {
  std::vector<std::uintmax_t> sizes;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(folder)) {
    if (entry.is_regular_file() && entry.path().filename().string().find(part) != std::string::npos) {
      sizes.push_back(entry.file_size());
    }
  }
  return sizes;
}

/// The file the run's error names (the text between "output error: " and the next ": "),
/// relative to `folder`, each run of digits as '#': the same for the same step of two runs.
std::string failed_step(const std::string& err, const std::filesystem::path& folder) {
  const std::string lead = "output error: " + folder.string() + "/";
  const std::size_t from = err.find(lead);
  if (from == std::string::npos) return {};
  const std::size_t start = from + lead.size();
  std::string step;
  for (const char c : err.substr(start, err.find(": ", start) - start)) {
    const bool digit = c >= '0' && c <= '9';
    if (!digit || step.empty() || step.back() != '#') step += digit ? '#' : c;
  }
  return step;
}

TEST(FailedWrite, StopsTheRunNamingTheFileAndTheReasonAndARerunWithRoomGivesTheBytesOfAnUnbrokenRun) {
  test::TempDir dir;
  const std::filesystem::path sim = dir / "sim";
  ASSERT_EQ(test::run_citymesh(fmt::format("simulate --out {} --length 30", sim.string())).exit_code, 0);
  const auto unbroken = test::run_citymesh(tiled_run_args(sim, "ref"));
  ASSERT_EQ(unbroken.exit_code, 0) << unbroken.err;
  const auto reference = test::result_bytes(sim / "ref");

  // Half the smallest tile store file: the tiler fails. Over every file of the work folder
  // (with room for a page of padding while a store file is written): the tiles are done, and
  // without labels mosaic.ply fails; with them, the pairs waiting on disk. One byte under
  // mosaic.ply: its last write fails.
  const std::vector<std::uintmax_t> store = file_sizes(sim / "work-ref/tiles", "blocks.bin");
  const std::vector<std::uintmax_t> work = file_sizes(sim / "work-ref", ""),
                                    mosaic = file_sizes(sim / "ref", "mosaic.ply");
  ASSERT_FALSE(store.empty());
  ASSERT_EQ(mosaic.size(), 1u);
  const std::uintmax_t past_work = *std::max_element(work.begin(), work.end()) + 65536;
  ASSERT_LT(past_work, mosaic[0]) << "the street's mosaic is no larger than its work files";
  const std::string no_labels = "--set output.labels=false";
  const std::vector<std::pair<std::uintmax_t, std::string>> failures = {
      {*std::min_element(store.begin(), store.end()) / 2, no_labels},
      {past_work, no_labels},
      {mosaic[0] - 1, no_labels},
      {past_work, ""}};

  std::set<std::string> failed_steps;
  for (const auto& [limit, extra] : failures) {
    const auto run = test::run_shell(fmt::format("trap '' XFSZ; exec prlimit --fsize={} {} {}", limit, CITYMESH_BINARY,
                                                 tiled_run_args(sim, "f", extra)));
    const std::string what = fmt::format("limit {} {}: {}", limit, extra, run.err);
    EXPECT_EQ(run.exit_code, 4) << what;
    EXPECT_NE(run.err.find("File too large"), std::string::npos) << what;
    const std::string step = failed_step(run.err, sim);
    EXPECT_FALSE(step.empty()) << what;
    failed_steps.insert(step);
  }
  // The tile store, mosaic.ply (twice) and the pairs.
  EXPECT_EQ(failed_steps.size(), 3u) << fmt::format("{}", fmt::join(failed_steps, ", "));

  const auto resumed = test::run_citymesh(tiled_run_args(sim, "f"));
  ASSERT_EQ(resumed.exit_code, 0) << resumed.err;
  EXPECT_TRUE(test::result_bytes(sim / "f") == reference) << "a run resumed after failed writes differs";
  // What the failed runs left (temporary files, pair and staging folders) went with the resumed run.
  for (const auto& entry : std::filesystem::recursive_directory_iterator(sim)) {
    const std::string name = entry.path().filename().string();
    const bool pair_folder = entry.is_directory() && name.starts_with("pairs.");
    EXPECT_TRUE(name.find(".tmp.") == std::string::npos && !pair_folder &&
                entry.path().parent_path().filename() != "staging")
        << entry.path() << " left by a failed run";
  }
}

}  // namespace
}  // namespace citymesh
