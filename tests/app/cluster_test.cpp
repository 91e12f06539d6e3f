// SPDX-License-Identifier: MIT
// Cluster runs through the binary: `mpirun -n 3 citymesh run` and subsets 1/3..3/3 plus
// `citymesh merge` give the same bytes as one process; a rank killed mid-run loses only its
// work in flight; merge refuses to assemble an unfinished run.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cstdlib>
#include <map>
#include <nlohmann/json.hpp>

#include "mesh_parts.h"
#include "test_support.h"

namespace citymesh {
namespace {

nlohmann::json read_json(const std::filesystem::path& path) { return nlohmann::json::parse(test::read_text(path)); }

std::string args(const std::string& sim, const std::string& name) {
  return fmt::format(
      "{}/config.toml --no-pictures --set project.output={} --set project.work=work-{} "
      "--set tiling.tile_size=10",
      sim, name, name);
}

/// The mosaic's summary without its timings: its counts and the stitching's figures (open
/// boundary before and after included), which must not depend on the ranks.
nlohmann::json summary_figures(const std::filesystem::path& output) {
  nlohmann::json s = read_json(output / "mosaic" / "summary.json");
  s.erase("seconds");
  s["stitch"].erase("seconds");
  return s;
}

/// How many items ranks 1 and 2 say they did in `log` after `said` ("rank N: <said>"), and
/// how many of them said it.
std::pair<std::size_t, std::size_t> done_by_other_ranks(const std::string& log, std::string_view said) {
  std::size_t items = 0, ranks = 0;
  for (const int rank : {1, 2}) {
    const std::string line = fmt::format("rank {}: {}", rank, said);
    const auto at = log.find(line);
    if (at == std::string::npos) continue;
    ++ranks;
    items += std::stoul(log.substr(at + line.size()));
  }
  return {items, ranks};
}

/// mpirun as the tests need it: root allowed (CI containers), more ranks than cores.
std::string mpirun(int ranks) {
  return fmt::format(
      "OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1 "
      "mpirun --oversubscribe -n {} {}",
      ranks, CITYMESH_BINARY);
}

bool have_mpi() {
#ifdef CITYMESH_WITH_MPI
  return std::system("command -v mpirun > /dev/null 2>&1") == 0;
#else
  return false;
#endif
}

/// The default street simulated once, with a one-process run as the reference.
class ClusterRun : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new test::TempDir;
    sim_ = (*dir_ / "sim").string();
    ASSERT_EQ(test::run_citymesh(fmt::format("simulate --out {}", sim_)).exit_code, 0);
    const auto one = test::run_citymesh("run " + args(sim_, "one"));
    ASSERT_EQ(one.exit_code, 0) << one.err;
    reference_ = new std::map<std::string, std::string>(test::result_bytes(*dir_ / "sim/one"));
  }
  static void TearDownTestSuite() {
    delete reference_;
    delete dir_;
  }
  static std::filesystem::path output(const std::string& name) { return *dir_ / "sim" / name; }

  static inline test::TempDir* dir_ = nullptr;
  static inline std::string sim_;
  static inline std::map<std::string, std::string>* reference_ = nullptr;
};

TEST_F(ClusterRun, ThreeMpiRanksGiveTheBytesOfOneProcess) {
  if (!have_mpi()) GTEST_SKIP() << "built without MPI or mpirun missing (tools/setup installs OpenMPI)";
  ASSERT_GE(reference_->size(), 7u);
  ASSERT_GE(read_json(output("one") / "run.json")["tiles"].get<int>(), 9);
  const std::string cmd =
      fmt::format("{} run {} > {} 2>&1", mpirun(3), args(sim_, "mpi"), (*dir_ / "mpi.log").string());
  ASSERT_EQ(std::system(cmd.c_str()), 0) << test::read_text(*dir_ / "mpi.log");
  EXPECT_TRUE(test::result_bytes(output("mpi")) == *reference_) << "3 ranks differ from one process";
  const nlohmann::json report = read_json(output("mpi") / "run.json");
  EXPECT_EQ(report["ranks"], 3);
  EXPECT_EQ(report["reused_tiles"], 0);
  // Run again with nothing new, every rank finds the outputs as they were: none is written.
  const std::string report_text = test::read_text(output("mpi") / "run.json");
  const std::string again =
      fmt::format("{} run {} > {} 2>&1", mpirun(3), args(sim_, "mpi"), (*dir_ / "mpi-again.log").string());
  ASSERT_EQ(std::system(again.c_str()), 0) << test::read_text(*dir_ / "mpi-again.log");
  EXPECT_NE(test::read_text(*dir_ / "mpi-again.log").find("nothing written"), std::string::npos)
      << test::read_text(*dir_ / "mpi-again.log");
  EXPECT_EQ(test::read_text(output("mpi") / "run.json"), report_text);
  EXPECT_TRUE(test::result_bytes(output("mpi")) == *reference_);
}

TEST_F(ClusterRun, ThreeMpiRanksShareTheFinalPassAndGiveTheBytesOfOneProcess) {
  if (!have_mpi()) GTEST_SKIP() << "built without MPI or mpirun missing (tools/setup installs OpenMPI)";
  // 20 m tiles take the seam pass by blocks (10 m ones are too narrow for its bands).
  const std::string blocks = " --set tiling.tile_size=20 --set run.seam_pass=blocks --threads 1";
  const auto one = test::run_citymesh("run " + args(sim_, "blocks-one") + blocks);
  ASSERT_EQ(one.exit_code, 0) << one.err;
  const std::string cmd = fmt::format("{} run {}{} > {} 2>&1", mpirun(3), args(sim_, "blocks-mpi"), blocks,
                                      (*dir_ / "blocks.log").string());
  ASSERT_EQ(std::system(cmd.c_str()), 0) << test::read_text(*dir_ / "blocks.log");
  EXPECT_TRUE(test::result_bytes(output("blocks-mpi")) == test::result_bytes(output("blocks-one")))
      << "3 ranks stitching differ from one process";
  // The figures too: the open boundary measured by the other ranks once came out longer
  // (they measured with a grid gone out of scope).
  EXPECT_EQ(summary_figures(output("blocks-mpi")), summary_figures(output("blocks-one")));
  // Ranks 1 and 2 each say how many tile results they read and filed, and how many parts
  // they stitched: some of each.
  const std::string log = test::read_text(*dir_ / "blocks.log");
  for (const std::string_view said : {"read and filed ", "stitched "}) {
    const auto [items, ranks] = done_by_other_ranks(log, said);
    EXPECT_EQ(ranks, 2u) << said << log;
    EXPECT_GT(items, 0u) << said << log;
  }
  EXPECT_FALSE(std::filesystem::exists(output("work-blocks-mpi") / "assembly-step.json")) << "the plan was left behind";
  EXPECT_FALSE(std::filesystem::exists(output("work-blocks-mpi") / "seam-level.json")) << "the plan was left behind";
  // They then file the output by grid tile, map leaves and build cells of the 3D Tiles tree
  // (the tiles are among the bytes compared above) until rank 0 ends; how many each gets
  // depends on timing.
  for (const int rank : {1, 2}) {
    EXPECT_NE(log.find(fmt::format("rank {}: filed ", rank)), std::string::npos) << log;
  }
  EXPECT_FALSE(std::filesystem::exists(output("work-blocks-mpi") / "output-step.json")) << "the plan was left behind";
}

TEST_F(ClusterRun, WithoutLabelsTheRanksAssembleTheTilesAndWriteTheTilePlysAndTheRootAddsUpWhatOneProcessCounts) {
  if (!have_mpi()) GTEST_SKIP() << "built without MPI or mpirun missing (tools/setup installs OpenMPI)";
  // Without labelled outputs rank 0 reads no tile result at all: it adds up the counts the
  // ranks that read them report (run.json, summary.json) and files what they filed.
  // The per-tile PLYs that go with it at city scale are written by every rank too.
  const std::string blocks =
      " --set tiling.tile_size=20 --set run.seam_pass=blocks --set output.labels=false --set output.ply=true "
      "--threads 1";
  const auto one = test::run_citymesh("run " + args(sim_, "tally-one") + blocks);
  ASSERT_EQ(one.exit_code, 0) << one.err;
  const std::string cmd =
      fmt::format("{} run {}{} > {} 2>&1", mpirun(3), args(sim_, "tally-mpi"), blocks, (*dir_ / "tally.log").string());
  ASSERT_EQ(std::system(cmd.c_str()), 0) << test::read_text(*dir_ / "tally.log");
  const auto bytes = test::result_bytes(output("tally-mpi"));
  EXPECT_TRUE(bytes == test::result_bytes(output("tally-one"))) << "3 ranks differ from one process";
  EXPECT_TRUE(bytes.contains("mosaic/mosaic.ply"));
  std::size_t tile_plys = 0;
  for (const auto& [name, content] : bytes) tile_plys += name.starts_with("ply/") ? 1 : 0;
  EXPECT_GE(tile_plys, 4u);
  EXPECT_EQ(summary_figures(output("tally-mpi")), summary_figures(output("tally-one")));
  const nlohmann::json run_one = read_json(output("tally-one") / "run.json"),
                       run_mpi = read_json(output("tally-mpi") / "run.json");
  for (const char* key : {"input_triangles", "output_triangles", "tiles"}) EXPECT_EQ(run_mpi[key], run_one[key]) << key;
  ASSERT_EQ(run_mpi["per_tile"].size(), run_one["per_tile"].size());
  for (std::size_t k = 0; k < run_one["per_tile"].size(); ++k) {
    for (const char* key : {"tile", "owned", "triangles"}) {
      EXPECT_EQ(run_mpi["per_tile"][k][key], run_one["per_tile"][k][key]) << k << key;
    }
    EXPECT_TRUE(run_mpi["per_tile"][k]["seconds"].contains("mosaic")) << "a processed tile's seconds came back";
  }
  const std::string log = test::read_text(*dir_ / "tally.log");
  const auto [items, ranks] = done_by_other_ranks(log, "read and filed ");
  EXPECT_EQ(ranks, 2u) << log;
  EXPECT_GT(items, 0u) << log;
  std::size_t plys_elsewhere = 0;
  for (const int rank : {1, 2}) {
    const auto line = log.find(fmt::format("rank {}: filed ", rank));
    const auto wrote = log.find("; wrote ", line);
    ASSERT_NE(wrote, std::string::npos) << log;
    plys_elsewhere += std::stoul(log.substr(wrote + 8));
  }
  EXPECT_GT(plys_elsewhere, 0u) << "no other rank wrote a per-tile PLY\n" << log;
  EXPECT_FALSE(std::filesystem::exists(output("work-tally-mpi") / "assembly-step.json")) << "the plan was left behind";
}

TEST_F(ClusterRun, AKilledRankLosesOnlyItsWorkInFlight) {
  if (!have_mpi()) GTEST_SKIP() << "built without MPI or mpirun missing (tools/setup installs OpenMPI)";
  // Kill the newest rank (SIGKILL) while the job runs, as soon as a first tile is finished
  // (waiting for it rather than a fixed time: on a loaded machine a fixed sleep killed it
  // before any tile was done): mpirun ends the job with an error.
  const std::filesystem::path script = *dir_ / "kill.sh";
  const std::string results = (output("work-kill") / "results").string();
  test::write_text(script,
                   fmt::format("{} run {} > /dev/null 2>&1 &\njob=$!\n"
                               "for i in $(seq 1200); do ls {}/*.bin > /dev/null 2>&1 && break; sleep 0.05; done\n"
                               "pkill -KILL -n -f 'citymesh run .*work-kill'\nwait $job\n",
                               mpirun(3), args(sim_, "kill"), results));
  EXPECT_NE(std::system(("bash " + script.string()).c_str()), 0) << "the job survived a killed rank";
  ASSERT_FALSE(std::filesystem::exists(output("kill") / "run.json")) << "killed too late to test anything";
  const std::string again =
      fmt::format("{} run {} > {} 2>&1", mpirun(3), args(sim_, "kill"), (*dir_ / "kill.log").string());
  ASSERT_EQ(std::system(again.c_str()), 0) << test::read_text(*dir_ / "kill.log");
  EXPECT_TRUE(test::result_bytes(output("kill")) == *reference_) << "the resumed job differs";
  const nlohmann::json report = read_json(output("kill") / "run.json");
  EXPECT_GT(report["reused_tiles"].get<int>(), 0) << "finished tiles were not kept";
}

TEST_F(ClusterRun, SubsetsThenMergeGiveTheBytesOfOneProcess) {
  const std::string run = args(sim_, "sub");
  const auto early = test::run_citymesh("merge " + run);
  EXPECT_EQ(early.exit_code, 2) << "merge before any subset";
  EXPECT_NE(early.err.find("--subset"), std::string::npos) << early.err;
  std::size_t own_tiles = 0;
  for (int i = 1; i <= 3; ++i) {
    const auto part = test::run_citymesh(fmt::format("run {} --subset {}/3", run, i));
    ASSERT_EQ(part.exit_code, 0) << part.err;
    EXPECT_NE(part.out.find(fmt::format("subset {}/3:", i)), std::string::npos) << part.out;
    EXPECT_FALSE(std::filesystem::exists(output("sub") / "mosaic")) << "a subset wrote outputs";
    if (i == 2) {
      // Subset 3 has not run: merge names what is missing and writes nothing.
      const auto partial = test::run_citymesh("merge " + run);
      EXPECT_EQ(partial.exit_code, 2);
      EXPECT_NE(partial.err.find("have no finished result"), std::string::npos) << partial.err;
      EXPECT_FALSE(std::filesystem::exists(output("sub") / "run.json"));
    }
    own_tiles += static_cast<std::size_t>(std::stoul(part.out.substr(part.out.find(" of its ") + 8)));
  }
  const nlohmann::json one = read_json(output("one") / "run.json");
  EXPECT_EQ(own_tiles, one["tiles"].get<std::size_t>()) << "every tile belongs to exactly one subset";
  const auto merged = test::run_citymesh("merge " + run);
  ASSERT_EQ(merged.exit_code, 0) << merged.err;
  EXPECT_TRUE(test::result_bytes(output("sub")) == *reference_) << "subsets + merge differ from one process";
  // Merged again, or run, with nothing new: the outputs are left as the merge wrote them.
  const std::string report = test::read_text(output("sub") / "run.json");
  for (const std::string command : {"merge ", "run "}) {
    const auto again = test::run_citymesh(command + run);
    ASSERT_EQ(again.exit_code, 0) << again.err;
    EXPECT_NE(again.out.find("nothing written"), std::string::npos) << command << again.out;
  }
  EXPECT_EQ(test::read_text(output("sub") / "run.json"), report);
}

TEST_F(ClusterRun, AnAppendedPassUnderMpiKeepsWhatOneProcessKeepsToTheSameBytes) {
  if (!have_mpi()) GTEST_SKIP() << "built without MPI or mpirun missing (tools/setup installs OpenMPI)";
  // The sixth pass over the first 21 m (as in TiledRun.AnAppendedAcquisition...): tiles of the
  // fourth column wait for the third, which it reaches, and are kept.
  ASSERT_TRUE(test::write_append_configs(*dir_ / "sim", 0.35));
  const auto config = [&](const char* file, const char* name) {
    return fmt::format(
        "{}/{} --no-pictures --set project.output={} --set project.work=work-{} "
        "--set tiling.tile_size=10",
        sim_, file, name, name);
  };
  std::map<std::string, nlohmann::json> reports;
  std::map<std::string, std::string> last_progress;  // "info: tiles 12/12 (12 reused)"
  for (const char* name : {"append-one", "append-mpi"}) {
    const auto five = test::run_citymesh("run " + config("five.toml", name));
    ASSERT_EQ(five.exit_code, 0) << five.err;
    const std::string six = std::string(name) == "append-one" ? std::string(CITYMESH_BINARY) : mpirun(3);
    const std::string cmd = fmt::format("{} run {} > {} 2>&1", six, config("six.toml", name),
                                        (*dir_ / (std::string(name) + ".log")).string());
    ASSERT_EQ(std::system(cmd.c_str()), 0) << test::read_text(*dir_ / (std::string(name) + ".log"));
    reports[name] = read_json(output(name) / "run.json");
    const std::string log = test::read_text(*dir_ / (std::string(name) + ".log"));
    const std::size_t line = log.rfind("info: tiles ");
    ASSERT_NE(line, std::string::npos) << log;
    last_progress[name] = log.substr(line, log.find(',', line) - line);
  }
  EXPECT_TRUE(test::result_bytes(output("append-mpi")) == test::result_bytes(output("append-one")))
      << "3 ranks appending differ from one process";
  // So do the progress lines: a tile another rank kept is reused, not processed.
  EXPECT_EQ(last_progress["append-mpi"], last_progress["append-one"]);
  EXPECT_GT(reports["append-one"]["kept_tiles"].get<int>(), 0);
  // The root counts the tiles the other ranks kept (their results say so).
  EXPECT_EQ(reports["append-mpi"]["kept_tiles"], reports["append-one"]["kept_tiles"]);
  EXPECT_EQ(reports["append-mpi"]["reused_tiles"], reports["append-one"]["reused_tiles"]);
}

TEST_F(ClusterRun, RanksRunningDifferentBuildsAreRefused) {
  if (!have_mpi()) GTEST_SKIP() << "built without MPI or mpirun missing (tools/setup installs OpenMPI)";
  // Each rank files its results under digests that hold its build: with two builds in one job
  // they would not find each other's work. mpirun's "A : B" starts one rank of each.
  const std::filesystem::path other = test::copy_as_another_build(dir_->path());
  const std::filesystem::path log = *dir_ / "two-builds.log";
  const std::string cmd = fmt::format("{} run {} : -n 1 {} run {} > {} 2>&1", mpirun(1), args(sim_, "two-builds"),
                                      other.string(), args(sim_, "two-builds"), log.string());
  EXPECT_NE(std::system(cmd.c_str()), 0);
  EXPECT_NE(test::read_text(log).find("different builds of citymesh"), std::string::npos) << test::read_text(log);
  EXPECT_FALSE(std::filesystem::exists(output("two-builds") / "run.json"));
}

TEST_F(ClusterRun, BadSubsetsAreUsageErrors) {
  for (const char* bad : {"0/3", "4/3", "x"}) {
    const auto r = test::run_citymesh(fmt::format("run {} --subset {}", args(sim_, "bad"), bad));
    EXPECT_EQ(r.exit_code, 1) << bad;
    EXPECT_NE(r.err.find("i/N"), std::string::npos) << r.err;
  }
}

}  // namespace
}  // namespace citymesh
