// SPDX-License-Identifier: MIT
// End to end through the binary: simulate the default street, run every step (and the
// update-model baseline), evaluate both against the ground truth. The mosaic issue's targets
// that hold today are asserted here; docs/mosaic.md lists the ones that do not yet.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <nlohmann/json.hpp>

#include "mosaic_ply.h"
#include "test_support.h"

namespace citymesh {
namespace {

nlohmann::json read_json(const std::filesystem::path& path) { return nlohmann::json::parse(test::read_text(path)); }

TEST(RunEval, DefaultStreetMosaicMeetsItsTargetsAndBeatsTheBaseline) {
  test::TempDir dir;
  const std::string sim = (dir / "sim").string();
  ASSERT_EQ(test::run_citymesh(fmt::format("simulate --out {}", sim)).exit_code, 0);
  const auto run = test::run_citymesh(fmt::format("run {}/config.toml", sim));
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const auto base = test::run_citymesh(
      fmt::format("run {}/config.toml --no-pictures --set mosaic.method=update-model --set project.output=base "
                  "--set project.work=work-base",
                  sim));
  ASSERT_EQ(base.exit_code, 0) << base.err;
  // The same mosaic practically unstitched (snapping within 1 cm, no clipping, no gap
  // closing): the reference for the seams stitching must close.
  const auto raw = test::run_citymesh(
      fmt::format("run {}/config.toml --no-pictures --set mosaic.stitch_reach=0.1 --set mosaic.clip_overlaps=false "
                  "--set mosaic.close_gaps=false --set project.output=raw --set project.work=work-raw",
                  sim));
  ASSERT_EQ(raw.exit_code, 0) << raw.err;
  for (const char* out : {"out", "base", "raw"}) {
    const auto eval = test::run_citymesh(fmt::format("eval {}/{} --truth {}", sim, out, sim));
    ASSERT_EQ(eval.exit_code, 0) << eval.err;
    EXPECT_NE(eval.out.find("overlap ratio"), std::string::npos);
  }
  const nlohmann::json m_eval = read_json(dir / "sim/out/eval.json"), b_eval = read_json(dir / "sim/base/eval.json");
  const nlohmann::json& m = m_eval.at("mosaic");
  const nlohmann::json& b = b_eval.at("mosaic");
  EXPECT_EQ(m["method"], "energy");
  EXPECT_EQ(b["method"], "update-model");

  EXPECT_LE(m["overlap_ratio"].get<double>(), 0.005);
  EXPECT_GE(m["static_completeness"].get<double>(), 0.998);  // 0.9958 without the hole fill
  EXPECT_LE(m["dynamic_residue"].get<double>(), 0.005);
  // Against the baseline: no more overlap, holes, open seams, coarser triangles or residue.
  EXPECT_LT(m["overlap_ratio"].get<double>(), b["overlap_ratio"].get<double>());
  EXPECT_LT(m["hole_ratio"].get<double>(), b["hole_ratio"].get<double>());
  EXPECT_LT(m["seam_length"].get<double>(), b["seam_length"].get<double>());
  EXPECT_LT(m["edge_length_ratio"].get<double>(), b["edge_length_ratio"].get<double>());
  EXPECT_LE(m["dynamic_residue"].get<double>(), b["dynamic_residue"].get<double>());
  // Not asserted, not met yet: static completeness against the baseline's (99.86 % against
  // 99.92 %; docs/mosaic.md, "What is not done yet").

  // Where the uncovered static area went adds up to it, in either method; what the change
  // step dropped is no more than the static area it did not keep.
  for (const auto& [name, whole] : {std::pair{"out", &m_eval}, std::pair{"base", &b_eval}}) {
    const nlohmann::json& mosaic = whole->at("mosaic");
    const nlohmann::json& u = mosaic["static_uncovered"];
    const double area = mosaic["static_area"].get<double>(), dropped = u["dropped_by_change_step"].get<double>();
    const double parts = dropped + u["kept_not_in_output"].get<double>() + u["in_output_cut_back"].get<double>();
    EXPECT_NEAR(parts, (1 - mosaic["static_completeness"].get<double>()) * area, 1e-6 * area) << name;
    const double not_kept = (1 - whole->at("static_completeness").get<double>()) * area;  // the change step's
    EXPECT_LE(dropped, not_kept + 1e-6 * area) << name;
    EXPECT_GT(dropped, 0.0) << name;
  }
  // The update model keeps every kept triangle that nothing kept before covers, so what it
  // leaves uncovered is what the change step dropped (stitching aside).
  const nlohmann::json& bu = b["static_uncovered"];
  EXPECT_LE(bu["kept_not_in_output"].get<double>() + bu["in_output_cut_back"].get<double>(),
            0.1 * bu["dropped_by_change_step"].get<double>());

  // Stitching leaves at most 5 % of the unstitched mosaic's open seams (4.7 % in session 21).
  const nlohmann::json u = read_json(dir / "sim/raw/eval.json")["mosaic"];
  EXPECT_LE(m["seam_length"].get<double>(), 0.05 * u["seam_length"].get<double>())
      << m["seam_length"] << " m left of " << u["seam_length"] << " m unstitched";

  // Stitching closed part of the open boundary; the output stays edge-manifold and every
  // face says where it came from.
  const nlohmann::json s = read_json(dir / "sim/out/mosaic/summary.json");
  EXPECT_LT(s["stitch"]["open_boundary_after_m"].get<double>(), s["stitch"]["open_boundary_before_m"].get<double>());
  EXPECT_GT(s["stitch"]["triangles_clipped"].get<std::uint64_t>(), 0u);  // pieces cut back where they overlapped
  EXPECT_GT(s["stitch"]["gaps_filled"].get<std::uint64_t>(), 0u);        // small holes between sources closed
  // Solved tile by tile: no whole-street energy (null rather than zeros); the counts of
  // triangles are the owned triangles' (tiled_run_test compares them with one tile's).
  EXPECT_TRUE(s["energy"].is_null());
  EXPECT_TRUE(s["counts"]["seam_terms"].is_null());
  EXPECT_GT(s["counts"]["filled"].get<std::uint64_t>(), 0u);
  EXPECT_GT(s["counts"]["seen_through"].get<std::uint64_t>(), 0u);
  EXPECT_GT(s["counts"]["candidates"].get<std::uint64_t>(), s["counts"]["selected"].get<std::uint64_t>());
  const auto [non_manifold, sources] = test::inspect_mosaic_ply(dir / "sim/out/mosaic/mosaic.ply");
  EXPECT_EQ(non_manifold, 0u);
  EXPECT_GT(sources.count(-1), 0u);  // stitch triangles
  EXPECT_GE(sources.size(), 3u);     // pieces of several acquisitions
  EXPECT_TRUE(std::filesystem::exists(dir / "sim/out/mosaic/mosaic.png"));
}

TEST(RunEval, DetectThenMosaicGivesTheSameBytesOnOneAndTwoThreads) {
  test::TempDir dir;
  const std::string sim = (dir / "sim").string();
  ASSERT_EQ(test::run_citymesh(fmt::format("simulate --out {} --length 30", sim)).exit_code, 0);
  std::string first;
  for (const int threads : {1, 2}) {
    ASSERT_EQ(
        test::run_citymesh(fmt::format("detect {}/config.toml --no-pictures --threads {}", sim, threads)).exit_code, 0);
    const auto mosaic =
        test::run_citymesh(fmt::format("mosaic {}/config.toml --no-pictures --threads {}", sim, threads));
    ASSERT_EQ(mosaic.exit_code, 0) << mosaic.err;
    const std::string bytes = test::read_text(dir / "sim/out/mosaic/mosaic.ply");
    if (threads == 1) first = bytes;
    EXPECT_TRUE(bytes == first) << "the mosaic differs between 1 and 2 threads";
  }
  // One solve over the whole street: its energy and counts are in the summary.
  const nlohmann::json s = read_json(dir / "sim/out/mosaic/summary.json");
  EXPECT_LT(s["energy"]["total"].get<double>(), 0.0);
  EXPECT_GT(s["counts"]["seam_terms"].get<std::uint64_t>(), 0u);
  EXPECT_GT(s["counts"]["filled"].get<std::uint64_t>(), 0u);
}

TEST(RunEval, MosaicRefusesAMissingOrDamagedDetectOutput) {
  test::TempDir dir;
  const std::string sim = (dir / "sim").string();
  ASSERT_EQ(test::run_citymesh(fmt::format("simulate --out {} --length 30", sim)).exit_code, 0);
  const auto missing = test::run_citymesh(fmt::format("mosaic {}/config.toml", sim));
  EXPECT_EQ(missing.exit_code, 2);
  EXPECT_NE(missing.err.find("run citymesh detect first"), std::string::npos) << missing.err;
  ASSERT_EQ(test::run_citymesh(fmt::format("detect {}/config.toml --no-pictures", sim)).exit_code, 0);
  const std::string pairs = test::read_text(dir / "sim/out/detect/pairs.bin");
  test::write_text(dir / "sim/out/detect/pairs.bin", pairs.substr(0, pairs.size() / 2));
  const auto damaged = test::run_citymesh(fmt::format("mosaic {}/config.toml", sim));
  EXPECT_EQ(damaged.exit_code, 2);
  EXPECT_NE(damaged.err.find("pairs.bin"), std::string::npos) << damaged.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "sim/out/mosaic/summary.json"));
}

TEST(RunEval, EvalRefusesAMosaicThatDoesNotMatchTheRun) {
  test::TempDir dir;
  const std::string sim = (dir / "sim").string();
  ASSERT_EQ(test::run_citymesh(fmt::format("simulate --out {} --length 30", sim)).exit_code, 0);
  ASSERT_EQ(test::run_citymesh(fmt::format("run {}/config.toml --no-pictures", sim)).exit_code, 0);
  test::write_text(dir / "sim/out/mosaic/summary.json", "{\"method\": \"energy\"}");
  const auto bad = test::run_citymesh(fmt::format("eval {}/out --truth {}", sim, sim));
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("mosaic"), std::string::npos) << bad.err;
}

TEST(RunEval, APassOfOverlappingTurnsGivesTheOutputOneLayer) {
  // A spinning scanner's turns are meshed one by one and overlap within each pass. Both `run`
  // (tiles) and `detect` + `mosaic` (pairs.bin) keep one layer of each pass; keeping every
  // layer, as before session 67, left ~90 % of the output over output of its own pass.
  test::TempDir dir;
  const std::string sim = (dir / "sim").string();
  ASSERT_EQ(
      test::run_citymesh(fmt::format("simulate --out {} --scanner spinning --length 30 --rings 8 --columns 256", sim))
          .exit_code,
      0);
  const auto run = test::run_citymesh(fmt::format("run {}/config.toml --no-pictures", sim));
  ASSERT_EQ(run.exit_code, 0) << run.err;
  ASSERT_EQ(
      test::run_citymesh(fmt::format("detect {}/config.toml --no-pictures --set project.output=whole", sim)).exit_code,
      0);
  ASSERT_EQ(
      test::run_citymesh(fmt::format("mosaic {}/config.toml --no-pictures --set project.output=whole", sim)).exit_code,
      0);
  for (const char* out : {"out", "whole"}) {
    const auto eval = test::run_citymesh(fmt::format("eval {}/{} --truth {}", sim, out, sim));
    ASSERT_EQ(eval.exit_code, 0) << eval.err;
    const nlohmann::json m = read_json(dir / "sim" / out / "eval.json").at("mosaic");
    EXPECT_LT(m["layered_ratio"].get<double>(), 0.08) << out;
    EXPECT_GT(m["static_completeness"].get<double>(), 0.98) << out;
    EXPECT_LT(m["hole_ratio"].get<double>(), 0.04) << out;
  }
}

}  // namespace
}  // namespace citymesh
