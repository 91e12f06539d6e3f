// SPDX-License-Identifier: MIT
// What `citymesh run --plan` says: the speed it takes from the last run's report and the lines
// it prints (the whole command is tested in tiled_run_test.cpp).
#include "run_plan.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>

namespace citymesh::app {
namespace {

TEST(RunPlan, TheSpeedIsTheProcessedTilesThreadSecondsOverTheirTriangles) {
  nlohmann::json report;
  report["per_tile"] = {
      {{"tile", "0_0"}, {"owned", 1000}, {"seconds", {{"read", 0.5}, {"detect", 1.5}, {"mosaic", 2.0}}}},
      {{"tile", "0_1"}, {"owned", 3000}, {"seconds", {{"read", 1.0}, {"detect", 2.0}, {"mosaic", 5.0}}}},
      // Reused: its work was done before, and counts neither way.
      {{"tile", "1_0"}, {"owned", 99999}, {"reused", true}}};
  report["seconds"] = {{"tiling", 1.0},   {"tiles", 7.0},  {"assembly", 0.5}, {"stitch", 2.0},
                       {"outputs", 0.25}, {"export", 1.0}, {"total", 11.75}};
  const LastRunSpeed speed = last_run_speed(report.dump());
  ASSERT_TRUE(speed.seconds_per_triangle.has_value());
  EXPECT_DOUBLE_EQ(*speed.seconds_per_triangle, (4.0 + 8.0) / 4000);
  ASSERT_TRUE(speed.final_pass_seconds.has_value());
  EXPECT_DOUBLE_EQ(*speed.final_pass_seconds, 3.75) << "the stages after the tiles'";

  report["per_tile"] = {{{"tile", "1_0"}, {"owned", 5}, {"reused", true}}};
  EXPECT_FALSE(last_run_speed(report.dump()).seconds_per_triangle) << "no tile processed";
  EXPECT_TRUE(last_run_speed(report.dump()).final_pass_seconds) << "its final pass ran";
  report["seconds"] = {{"assembly", 0.5}, {"export", 1.0}, {"total", 1.5}};
  EXPECT_DOUBLE_EQ(*last_run_speed(report.dump()).final_pass_seconds, 1.5) << "merge's report: no tiles stage";
  EXPECT_FALSE(last_run_speed("{\"tiles\": 3").final_pass_seconds) << "damaged";
  EXPECT_FALSE(last_run_speed("{\"tiles\": 3}").seconds_per_triangle) << "no per_tile";
}

TEST(RunPlan, TheLinesSayTheCountsTheTilesToProcessAndTheTimeRange) {
  RunPlan plan;
  plan.tiles = 40;
  plan.to_process = 14;
  plan.may_be_kept = 6;
  plan.reused = 20;
  plan.triangles_to_process = 10'000'000;
  plan.triangles_may_be_kept = 5'000'000;
  for (int k = 0; k < 14; ++k) plan.names_to_process.push_back("0_" + std::to_string(k));
  plan.last_run = {.seconds_per_triangle = 4e-6, .final_pass_seconds = 12.3};
  const std::string text = describe_plan(plan, 2);
  EXPECT_NE(text.find("plan: 40 tiles: 14 to process (10000000 input triangles), 6 kept unless a tile they wait "
                      "for decides otherwise about their halo (5000000 input triangles), 20 reused\n"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("plan: to process: 0_0, 0_1, 0_2, 0_3, 0_4, 0_5, 0_6, 0_7, 0_8, 0_9, 0_10, 0_11 and 2 more\n"),
            std::string::npos)
      << text;
  // 10 M triangles at 4 µs on 2 threads, up to 15 M if none is kept.
  EXPECT_NE(text.find("the tiles would take 20.0 to 30.0 s on 2 thread(s)"), std::string::npos) << text;
  EXPECT_NE(text.find("then the final pass, over the whole output (12.3 s in the last run)"), std::string::npos)
      << text;

  plan.may_be_kept = 0;
  plan.triangles_may_be_kept = 0;
  plan.last_run = {};
  const std::string bare = describe_plan(plan, 2);
  EXPECT_EQ(bare.find("kept unless"), std::string::npos) << bare;
  EXPECT_NE(bare.find("no estimate of the time"), std::string::npos) << bare;

  const RunPlan done{.tiles = 40, .reused = 40};
  EXPECT_NE(describe_plan(done, 1).find("every tile's result is reused"), std::string::npos);
}

}  // namespace
}  // namespace citymesh::app
