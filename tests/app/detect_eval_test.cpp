// SPDX-License-Identifier: MIT
// End to end through the binary: simulate the default street, detect, evaluate against the
// ground truth. The targets are asserted here.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <nlohmann/json.hpp>

#include "test_support.h"

namespace citymesh {
namespace {

nlohmann::json read_json(const std::filesystem::path& path) { return nlohmann::json::parse(test::read_text(path)); }

TEST(DetectEval, DefaultStreetMeetsTheRemovalAndCompletenessTargets) {
  test::TempDir dir;
  const std::string sim = (dir / "sim").string();
  ASSERT_EQ(test::run_citymesh(fmt::format("simulate --out {}", sim)).exit_code, 0);
  // Faces on no surface (bridging depth jumps) are drawn too, not rejected.
  EXPECT_EQ(test::run_citymesh(fmt::format("render --sim {} --epoch 3 --color class --out {}/e3.png", sim, sim)).exit_code, 0);
  const auto detect = test::run_citymesh(fmt::format("detect {}/config.toml", sim));
  ASSERT_EQ(detect.exit_code, 0) << detect.err;
  const auto eval = test::run_citymesh(fmt::format("eval {}/out --truth {}", sim, sim));
  ASSERT_EQ(eval.exit_code, 0) << eval.err;
  EXPECT_NE(eval.out.find("static completeness"), std::string::npos);

  const nlohmann::json e = read_json(dir / "sim/out/eval.json");
  // Ts = 30 days (the simulator's config): every object that must go is >= 99 % removed and
  // >= 99 % of the static structure's area is kept.
  EXPECT_GE(e["static_completeness"].get<double>(), 0.99);
  EXPECT_GE(e["dynamic_removed_worst_object"].get<double>(), 0.99);
  EXPECT_LE(e["dynamic_residue"].get<double>(), 0.01);
  int removed_objects = 0;
  for (const auto& o : e["objects"]) removed_objects += o["fate"] == "remove" ? 1 : 0;
  EXPECT_GE(removed_objects, 20);  // the scripted changes are all there

  const nlohmann::json s = read_json(dir / "sim/out/detect/summary.json");
  ASSERT_EQ(s["acquisitions"].size(), 6u);
  for (const auto& a : s["acquisitions"]) {
    EXPECT_TRUE(std::filesystem::exists(dir / "sim/out/detect" / a["png"].get<std::string>()));
    const auto& c = a["counts"];
    EXPECT_EQ(c["consistent"].get<std::uint64_t>() + c["conflicting"].get<std::uint64_t>() +
                  c["single"].get<std::uint64_t>(),
              a["triangles"].get<std::uint64_t>());
  }
  // Only older acquisitions can conflict: the newest one never does.
  EXPECT_EQ(s["acquisitions"][5]["counts"]["conflicting"].get<std::uint64_t>(), 0u);
  EXPECT_GT(s["prefilter"]["skipped"].get<std::uint64_t>(), 0u);
}

TEST(DetectEval, StrictPolicyKeepsLessNearestSampleConflictsLessAndSameInputGivesSameBytes) {
  test::TempDir dir;
  const std::string sim = (dir / "sim").string();
  ASSERT_EQ(test::run_citymesh(fmt::format("simulate --out {} --length 30", sim)).exit_code, 0);
  ASSERT_EQ(test::run_citymesh(fmt::format("detect {}/config.toml --no-pictures --threads 1", sim)).exit_code, 0);
  const std::string one = test::read_text(dir / "sim/out/detect/2_epoch 2.ply");
  ASSERT_EQ(test::run_citymesh(fmt::format("detect {}/config.toml --no-pictures --threads 2", sim)).exit_code, 0);
  EXPECT_EQ(test::read_text(dir / "sim/out/detect/2_epoch 2.ply"), one);
  const auto kept = [&] { return read_json(dir / "sim/out/detect/summary.json")["totals"]["kept"].get<std::uint64_t>(); };
  const std::uint64_t default_kept = kept();
  const auto conflicting = [&] {
    return read_json(dir / "sim/out/detect/summary.json")["totals"]["conflicting"].get<std::uint64_t>();
  };
  const std::uint64_t default_conflicting = conflicting();
  ASSERT_EQ(test::run_citymesh(fmt::format("detect {}/config.toml --no-pictures --set change.unconfirmed=drop", sim)).exit_code, 0);
  EXPECT_LT(kept(), default_kept);
  // Empty spaces cut at the nearest corner's range claim less: fewer conflicts, and the
  // summary says which reach was used.
  ASSERT_EQ(test::run_citymesh(
                fmt::format("detect {}/config.toml --no-pictures --set change.empty_space=nearest-sample", sim))
                .exit_code,
            0);
  EXPECT_LT(conflicting(), default_conflicting);
  EXPECT_GT(conflicting(), 0u);
  EXPECT_EQ(read_json(dir / "sim/out/detect/summary.json")["empty_space"], "nearest-sample");
}

TEST(DetectEval, BadInputsGiveClearErrors) {
  test::TempDir dir;
  const auto missing = test::run_citymesh(fmt::format("eval {} --truth {}", dir.path().string(), dir.path().string()));
  EXPECT_EQ(missing.exit_code, 2);
  EXPECT_NE(missing.err.find("summary.json"), std::string::npos) << missing.err;
  test::write_text(dir / "c.toml", "[project]\ncrs = \"EPSG:2154\"\nvertical_datum = \"ellipsoidal\"\n"
                                   "[change]\nunconfirmed = \"maybe\"\n");
  const auto bad = test::run_citymesh(fmt::format("detect {}", (dir / "c.toml").string()));
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_NE(bad.err.find("unconfirmed"), std::string::npos) << bad.err;
}

}  // namespace
}  // namespace citymesh
