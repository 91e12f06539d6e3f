// SPDX-License-Identifier: MIT
// The citymesh binary as a user runs it.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "citymesh/config/config.h"
#include "test_support.h"

namespace citymesh {
namespace {

TEST(Cli, HelpListsEveryCommandAndOptionWithDefaults) {
  const auto top = test::run_citymesh("--help");
  EXPECT_EQ(top.exit_code, 0);
  for (const char* command : {"info", "config"}) EXPECT_NE(top.out.find(command), std::string::npos);
  const auto info = test::run_citymesh("info --help");
  EXPECT_EQ(info.exit_code, 0);
  for (const char* option : {"--config", "--crs", "--sensor-origin", "--require-origin", "--json", "Examples:"}) {
    EXPECT_NE(info.out.find(option), std::string::npos) << option;
  }
  const auto config = test::run_citymesh("config --help");
  for (const char* option : {"--dump-defaults", "--check", "--print", "--set", "--no-file-check", "Examples:"}) {
    EXPECT_NE(config.out.find(option), std::string::npos) << option;
  }
}

TEST(Cli, UsageErrorsExitWithOne) {
  EXPECT_EQ(test::run_citymesh("").exit_code, 1);
  EXPECT_EQ(test::run_citymesh("frobnicate").exit_code, 1);
  EXPECT_EQ(test::run_citymesh("info --no-such-flag x").exit_code, 1);
  const auto r = test::run_citymesh("info");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("no files given"), std::string::npos) << r.err;
}

TEST(Cli, DumpDefaultsGoesToStdoutAndMatchesTheLibrary) {
  const auto r = test::run_citymesh("config --dump-defaults");
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_EQ(r.out, dump_default_config());
}

TEST(Cli, DemoConfigChecksAndDescribesItsAcquisitions) {
  const auto demo = (test::source_dir() / "configs/demo.toml").string();
  const auto check = test::run_citymesh("config --check " + demo);
  EXPECT_EQ(check.exit_code, 0) << check.err;
  EXPECT_NE(check.out.find("ok: "), std::string::npos);
  const auto info = test::run_citymesh("info --json --config " + demo);
  ASSERT_EQ(info.exit_code, 0) << info.err;
  std::istringstream lines(info.out);
  std::string line;
  int files = 0;
  while (std::getline(lines, line)) {
    const auto j = nlohmann::json::parse(line);
    EXPECT_TRUE(j["sensor_origin"].get<bool>());
    EXPECT_GT(j["triangles"].get<int>(), 0);
    const double lat = j["lat_lon_bounds"]["lat"][0].get<double>();
    EXPECT_NEAR(lat, 48.84, 0.05);  // the demo street is in Paris
    ++files;
  }
  EXPECT_GE(files, 2);
}

TEST(Cli, InfoOnTheRealStereopolisSample) {
  const auto dir = test::real_data_dir();
  if (dir.empty()) GTEST_SKIP() << "real data absent";
  const auto file = dir / "terramobilita_riegl_paris2013/sample_riegl_18_01.ply";
  const auto r = test::run_citymesh("info --json --crs EPSG:2154 " + file.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["elements"][0]["count"].get<int>(), 30000);
  EXPECT_NEAR(j["bounds"]["min"][0].get<double>(), 651070, 50);
  EXPECT_NEAR(j["bounds"]["min"][1].get<double>(), 6860700, 100);
  EXPECT_NEAR(j["lat_lon_bounds"]["lon"][0].get<double>(), 2.333, 0.01);
  const auto text = test::run_citymesh("info --crs EPSG:2154 " + file.string());
  EXPECT_NE(text.out.find("vertex: 30000 rows"), std::string::npos) << text.out;
  EXPECT_NE(text.out.find("x 6510"), std::string::npos) << text.out;
}

TEST(Cli, LogJsonWritesOneObjectPerLine) {
  const auto r = test::run_citymesh("--log-json info " + (test::source_dir() / "tests/data/bad/empty.ply").string());
  EXPECT_EQ(r.exit_code, 2);
  const auto j = nlohmann::json::parse(r.err.substr(0, r.err.find('\n')));
  EXPECT_EQ(j["level"], "error");
  EXPECT_NE(j["msg"].get<std::string>().find("not a PLY file"), std::string::npos);
}

}  // namespace
}  // namespace citymesh
