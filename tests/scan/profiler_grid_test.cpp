// SPDX-License-Identifier: MIT
// The profiler grid on synthetic scan lines (the real samples' test is skipped without them).
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>

#include "citymesh/core/error.h"
#include "citymesh/scan/real_scans.h"
#include "test_support.h"

namespace citymesh {
namespace {

constexpr int kLines = 5, kBins = 360;  // a pulse every degree

/// A profiler at (651000 + 0.1 line, 6860000, 40) turning in the x = const plane: line l, bin
/// b at angle b degrees, 5 m away; every third pulse has a second echo 1 m further, and the
/// pulses of bin 7 of line 2 are missing. Lines [first, last) as ASCII PLY.
void write_lines(const std::filesystem::path& path, int first, int last) {
  std::string body;
  int rows = 0;
  for (int line = first; line < last; ++line) {
    for (int bin = 0; bin < kBins; ++bin) {
      if (line == 2 && bin == 7) continue;
      const double angle = bin * M_PI / 180.0, sx = 651000 + 0.1 * line;
      const int echoes = bin % 3 == 0 ? 2 : 1;
      for (int echo = 1; echo <= echoes; ++echo) {
        const double range = 5.0 + (echo - 1);
        const double reported = angle;  // in [0, 2 pi): the angle wraps where a line starts
        body += fmt::format("{:.4f} {:.4f} {:.4f} {:.4f} 6860000 40 {} {} {} {:.6f}\n", sx,
                            6860000 + range * std::cos(angle), 40 + range * std::sin(angle), sx, reported + 1e-9, echo,
                            echoes, 100.0 + line + bin * 1e-4);
        ++rows;
      }
    }
  }
  test::write_text(path, fmt::format("ply\nformat ascii 1.0\nelement vertex {}\nproperty double x\nproperty double y\n"
                                     "property double z\nproperty double x_origin\nproperty double y_origin\n"
                                     "property double z_origin\nproperty double theta\nproperty int num_echo\n"
                                     "property int nb_of_echo\nproperty double gps_time\nend_header\n{}",
                                     rows, body));
}

void expect_the_synthetic_grid(const SensorGrid& g) {
  EXPECT_EQ(g.cols, static_cast<std::size_t>(kBins));
  ASSERT_EQ(g.rows, static_cast<std::size_t>(kLines));
  std::size_t valid = 0;
  for (const std::uint8_t v : g.valid) valid += v;
  EXPECT_EQ(valid, static_cast<std::size_t>(kLines * kBins - 1));
  EXPECT_EQ(g.origin, Vec3d(651000, 6860005, 40));  // the first point's whole metres
  // Line 1's pulse at bin 30 (angle 30°), its first echo.
  const std::size_t cell = g.index(1, 30);
  ASSERT_TRUE(g.valid[cell]);
  const Vec3d p = g.origin + Vec3d(g.points[cell]);
  EXPECT_NEAR(p.x, 651000.1, 1e-3);
  EXPECT_NEAR(p.y, 6860000 + 5 * std::cos(M_PI / 6), 1e-3);
  EXPECT_NEAR(p.z, 40 + 5 * std::sin(M_PI / 6), 1e-3);
  EXPECT_NEAR(g.times[cell], 101.003, 1e-9);
  EXPECT_FALSE(g.valid[g.index(2, 7)]) << "line 2's missing pulse";
}

TEST(ProfilerGrid, LinesWrapAnglesAndFirstEchoesLandInTheirCells) {
  test::TempDir dir;
  write_lines(dir / "all.ply", 0, kLines);
  expect_the_synthetic_grid(profiler_grid({dir / "all.ply"}, {}));
}

TEST(ProfilerGrid, ChunksOfOneDriveGiveTheGridOfOneFile) {
  test::TempDir dir;
  write_lines(dir / "all.ply", 0, kLines);
  write_lines(dir / "a.ply", 0, 2);
  write_lines(dir / "b.ply", 2, kLines);
  const SensorGrid whole = profiler_grid({dir / "all.ply"}, {});
  const SensorGrid chunks = profiler_grid({dir / "a.ply", dir / "b.ply"}, {});
  expect_the_synthetic_grid(chunks);
  EXPECT_EQ(chunks.valid, whole.valid);
  EXPECT_EQ(chunks.points, whole.points);
  EXPECT_EQ(chunks.times, whole.times);
}

TEST(ProfilerGrid, LastEchoesAreTakenWhenAsked) {
  test::TempDir dir;
  write_lines(dir / "all.ply", 0, kLines);
  ProfilerGridParams last;
  last.echo = ProfilerGridParams::Echo::last;
  const SensorGrid g = profiler_grid({dir / "all.ply"}, last);
  const std::size_t cell = g.index(1, 30);  // bin 30 has two echoes: the second is 6 m away
  ASSERT_TRUE(g.valid[cell]);
  EXPECT_NEAR(norm(Vec3d(g.points[cell]) - Vec3d(g.sensors[cell])), 6.0, 1e-3);
}

TEST(ProfilerGrid, TooFewPulsesAreAnInputError) {
  test::TempDir dir;
  test::write_text(dir / "one.ply",
                   "ply\nformat ascii 1.0\nelement vertex 1\nproperty double x\nproperty double y\nproperty double z\n"
                   "property double x_origin\nproperty double y_origin\nproperty double z_origin\n"
                   "property double theta\nproperty int num_echo\nproperty int nb_of_echo\nend_header\n"
                   "1 2 3 0 0 0 0.5 1 1\n");
  EXPECT_THROW(profiler_grid({dir / "one.ply"}, {}), InputError);
}

}  // namespace
}  // namespace citymesh
