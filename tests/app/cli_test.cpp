// SPDX-License-Identifier: MIT
// The citymesh binary as a user runs it.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <vector>

#include "citymesh/config/config.h"
#include "citymesh/io/mesh_io.h"
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
    EXPECT_TRUE(j["within_crs_area"].get<bool>());
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

/// A config of two acquisitions, `first` and `second` (files in `dir`), in Lambert-93.
void write_two_pass_config(const std::filesystem::path& config, const std::string& first, const std::string& second) {
  test::write_text(config, fmt::format("[project]\ncrs = \"EPSG:2154\"\nvertical_datum = \"ellipsoidal\"\n"
                                       "[[acquisition]]\npath = \"{}\"\ntime = \"2026-01-01T00:00:00Z\"\n"
                                       "[[acquisition]]\npath = \"{}\"\ntime = \"2026-02-01T00:00:00Z\"\n",
                                       first, second));
}

/// Three points with sensor positions, as ASCII PLY, and `faces` (may be empty) after them:
/// with `face_element` false, no face element at all (a point cloud).
void write_three_points(const std::filesystem::path& path, bool face_element, const std::string& faces = "") {
  const int face_count = static_cast<int>(std::count(faces.begin(), faces.end(), '\n'));
  test::write_text(path, fmt::format("ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\nproperty double y\n"
                                     "property double z\nproperty double x_origin\nproperty double y_origin\n"
                                     "property double z_origin\n{}end_header\n"
                                     "651000 6860000 30 651000 6859990 32\n651001 6860000 30 651000 6859990 32\n"
                                     "651000 6860001 30 651000 6859990 32\n{}",
                                     face_element ? fmt::format("element face {}\nproperty list uchar int "
                                                                "vertex_indices\n",
                                                                face_count)
                                                  : std::string(),
                                     faces));
}

/// `config --check`, `detect` and `run` of `config` (in `dir`) each stop with exit code 2 and
/// an error holding every one of `phrases`, and no output is begun.
void expect_refused_before_any_work(const std::filesystem::path& dir, const std::string& config,
                                    const std::vector<std::string>& phrases) {
  for (const char* command : {"config --check", "detect", "run --no-pictures"}) {
    const auto r = test::run_citymesh(fmt::format("{} {}", command, config));
    EXPECT_EQ(r.exit_code, 2) << command << ": " << r.err;
    for (const std::string& phrase : phrases) {
      EXPECT_NE(r.err.find(phrase), std::string::npos) << command << ": " << r.err;
    }
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "out/mosaic")) << "no output begun";
}

TEST(Cli, APointCloudGivenAsAnAcquisitionIsRefusedByNameBeforeAnyWork) {
  test::TempDir dir;
  write_three_points(dir / "mesh.ply", true, "3 0 1 2\n");
  write_three_points(dir / "points.ply", false);
  write_two_pass_config(dir / "run.toml", "mesh.ply", "points.ply");
  const std::string config = (dir / "run.toml").string();
  expect_refused_before_any_work(dir.path(), config, {"points.ply: no face element: a point cloud, not a mesh"});
  // `--no-file-check` reads no file.
  EXPECT_EQ(test::run_citymesh("config --no-file-check --check " + config).exit_code, 0);
}

TEST(Cli, ARunWhoseAcquisitionsHoldNoTriangleSaysSoAtItsStart) {
  test::TempDir dir;
  write_three_points(dir / "a.ply", true);  // a face element of no face
  write_three_points(dir / "b.ply", true);
  write_two_pass_config(dir / "run.toml", "a.ply", "b.ply");
  const auto r = test::run_citymesh("run --no-pictures " + (dir / "run.toml").string());
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("run.toml: the acquisitions hold no triangle"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "out/mosaic")) << "no output begun";
}

TEST(Cli, AnAcquisitionInAnotherCrsIsRefusedByNameBeforeAnyWork) {
  test::TempDir dir;
  write_three_points(dir / "lambert.ply", true, "3 0 1 2\n");
  // The same triangle with longitude and latitude written where metres belong.
  std::string degrees = test::read_text(dir / "lambert.ply");
  for (const auto& [from, to] :
       std::vector<std::pair<std::string, std::string>>{{"651000 6860000 ", "2.3500 48.8500 "},
                                                        {"651001 6860000 ", "2.3501 48.8500 "},
                                                        {"651000 6860001 ", "2.3500 48.8501 "},
                                                        {"651000 6859990 ", "2.3500 48.8499 "}}) {
    for (std::size_t at = degrees.find(from); at != std::string::npos; at = degrees.find(from, at)) {
      degrees.replace(at, from.size(), to);
    }
  }
  // Every pass so: a pass in another CRS than the others is refused anyway (too far from the
  // first one's frame), but not when all of them are.
  test::write_text(dir / "degrees.ply", degrees);
  test::write_text(dir / "degrees2.ply", degrees);
  write_two_pass_config(dir / "run.toml", "degrees.ply", "degrees2.ply");
  const std::string config = (dir / "run.toml").string();
  expect_refused_before_any_work(dir.path(), config,
                                 {"degrees.ply: a vertex at x 2.35, y 48.85 lies at lat",
                                  "outside the area EPSG:2154 (RGF93 / Lambert-93) is meant for"});
  // `info` describes them, and says where they fall.
  const auto info = test::run_citymesh("info --json --config " + config);
  ASSERT_EQ(info.exit_code, 0) << info.err;
  EXPECT_FALSE(nlohmann::json::parse(info.out.substr(0, info.out.find('\n')))["within_crs_area"].get<bool>());
  // Lambert-93 metres in a local frame at Paris are refused too.
  test::write_text(dir / "lambert2.ply", test::read_text(dir / "lambert.ply"));
  write_two_pass_config(dir / "run.toml", "lambert.ply", "lambert2.ply");
  std::string enu = test::read_text(dir / "run.toml");
  enu.replace(enu.find("EPSG:2154"), 9, "ENU:48.8566,2.3522,35");
  test::write_text(dir / "enu.toml", enu);
  const auto local = test::run_citymesh("config --check " + (dir / "enu.toml").string());
  EXPECT_EQ(local.exit_code, 2) << local.err;
  EXPECT_NE(local.err.find("lambert.ply: a vertex at x 651000.00"), std::string::npos) << local.err;
}

TEST(Cli, ABudgetPastTheMachinesMemoryIsWarnedOf) {
  test::TempDir dir;
  write_three_points(dir / "a.ply", true, "3 0 1 2\n");
  write_three_points(dir / "b.ply", true, "3 0 1 2\n");
  write_two_pass_config(dir / "run.toml", "a.ply", "b.ply");
  const std::string config = (dir / "run.toml").string();
  constexpr const char* kWarning = "is more than this machine's memory";
  const auto past = test::run_citymesh("run --no-pictures --memory 1000TiB " + config);
  EXPECT_EQ(past.exit_code, 0) << past.err;
  EXPECT_NE(past.err.find(kWarning), std::string::npos) << past.err;
  const auto within = test::run_citymesh("run --no-pictures --memory 1GiB " + config);
  EXPECT_EQ(within.exit_code, 0) << within.err;
  EXPECT_EQ(within.err.find(kWarning), std::string::npos) << within.err;
}

/// A spinning sensor's frame at (sx, 0, 1.5): 8 rings from -10 to +10 degrees, 64 columns,
/// every return 6 m away (a round wall about the sensor), as ASCII PLY with ring and column.
void write_spinning_frame(const std::filesystem::path& path, double sx) {
  std::string body;
  int count = 0;
  for (int ring = 0; ring < 8; ++ring) {
    for (int column = 0; column < 64; ++column) {
      const double elevation = (-10.0 + 20.0 * ring / 7) * M_PI / 180, azimuth = 2 * M_PI * column / 64;
      const double x = sx + 6 * std::cos(elevation) * std::cos(azimuth),
                   y = 6 * std::cos(elevation) * std::sin(azimuth), z = 1.5 + 6 * std::sin(elevation);
      body += fmt::format("{:.4f} {:.4f} {:.4f} {:.4f} 0 1.5 {} {} 1\n", x, y, z, sx, ring, column);
      ++count;
    }
  }
  test::write_text(path, fmt::format("ply\nformat ascii 1.0\nelement vertex {}\nproperty double x\nproperty double y\n"
                                     "property double z\nproperty double x_origin\nproperty double y_origin\n"
                                     "property double z_origin\nproperty int ring\nproperty int column\n"
                                     "property int valid\nend_header\n{}",
                                     count, body));
}

TEST(Cli, MeshMakesAProfilerDriveBandByBandWithTheBytesOfOneBand) {
  test::TempDir dir;
  test::write_profiler_lines(dir / "a.ply", 0, 2);
  test::write_profiler_lines(dir / "b.ply", 2, test::kProfilerLines);
  const std::string files = fmt::format("{0}/a.ply {0}/b.ply", dir.path().string());
  const auto whole = test::run_citymesh(fmt::format("mesh {} --out {}/whole.ply", files, dir.path().string()));
  ASSERT_EQ(whole.exit_code, 0) << whole.err;
  EXPECT_NE(whole.out.find("grid 5 x 360, 1799 points"), std::string::npos) << whole.out;
  const Mesh mesh = read_mesh(dir / "whole.ply").mesh;
  EXPECT_GT(mesh.triangle_count(), 2u * 4 * 350);  // four quads' rows around the circle, but for a few
  for (const int lines : {2, 3, 4}) {
    const auto bands = test::run_citymesh(
        fmt::format("mesh {} --band-lines {} --out {}/bands.ply", files, lines, dir.path().string()));
    ASSERT_EQ(bands.exit_code, 0) << bands.err;
    EXPECT_EQ(bands.out, whole.out.substr(0, whole.out.find("whole.ply")) +
                             whole.out.substr(whole.out.find("whole.ply")).replace(0, 9, "bands.ply"));
    EXPECT_EQ(test::read_text(dir / "bands.ply"), test::read_text(dir / "whole.ply")) << lines;
  }
}

TEST(Cli, MeshPutsTheSpinningFramesOfOneDriveInOneMeshEachMeshedOnItsOwn) {
  test::TempDir dir;
  write_spinning_frame(dir / "f1.ply", 0.0);
  write_spinning_frame(dir / "f2.ply", 0.05);
  for (const char* name : {"f1", "f2"}) {
    const auto one =
        test::run_citymesh(fmt::format("mesh {0}/{1}.ply --out {0}/{1}_mesh.ply", dir.path().string(), name));
    ASSERT_EQ(one.exit_code, 0) << one.err;
  }
  const auto both =
      test::run_citymesh(fmt::format("mesh {0}/f1.ply {0}/f2.ply --out {0}/drive.ply", dir.path().string()));
  ASSERT_EQ(both.exit_code, 0) << both.err;
  EXPECT_NE(both.out.find("2 frame(s)"), std::string::npos) << both.out;
  const Mesh f1 = read_mesh(dir / "f1_mesh.ply").mesh, f2 = read_mesh(dir / "f2_mesh.ply").mesh;
  const Mesh drive = read_mesh(dir / "drive.ply").mesh;
  ASSERT_GT(f1.triangle_count(), 500u);
  ASSERT_EQ(drive.triangle_count(), f1.triangle_count() + f2.triangle_count());
  ASSERT_EQ(drive.vertex_count(), f1.vertex_count() + f2.vertex_count());
  // The first frame's triangles, then the second's, the same corners (world coordinates) and
  // sensor positions as meshed alone: no triangle joins the two frames.
  for (std::size_t t = 0; t < drive.triangle_count(); ++t) {
    const bool first = t < f1.triangle_count();
    const Mesh& alone = first ? f1 : f2;
    const std::size_t u = first ? t : t - f1.triangle_count();
    for (int k = 0; k < 3; ++k) {
      const Vec3d a = drive.world_position(drive.triangles[t][k]), b = alone.world_position(alone.triangles[u][k]);
      ASSERT_LT(norm(a - b), 1e-4) << t;
      const Vec3d sa = drive.world_sensor_position(drive.triangles[t][k]);
      const Vec3d sb = alone.world_sensor_position(alone.triangles[u][k]);
      ASSERT_LT(norm(sa - sb), 1e-4) << t;
    }
  }
}

}  // namespace
}  // namespace citymesh
