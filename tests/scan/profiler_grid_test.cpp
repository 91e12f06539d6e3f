// SPDX-License-Identifier: MIT
// The profiler grid on synthetic scan lines (the real samples' test is skipped without them).
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "citymesh/core/error.h"
#include "citymesh/scan/real_scans.h"
#include "test_support.h"

namespace citymesh {
namespace {

constexpr int kLines = test::kProfilerLines, kBins = test::kProfilerBins;

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
  test::write_profiler_lines(dir / "all.ply", 0, kLines);
  expect_the_synthetic_grid(profiler_grid({dir / "all.ply"}, {}));
}

TEST(ProfilerGrid, ChunksOfOneDriveGiveTheGridOfOneFile) {
  test::TempDir dir;
  test::write_profiler_lines(dir / "all.ply", 0, kLines);
  test::write_profiler_lines(dir / "a.ply", 0, 2);
  test::write_profiler_lines(dir / "b.ply", 2, kLines);
  const SensorGrid whole = profiler_grid({dir / "all.ply"}, {});
  const SensorGrid chunks = profiler_grid({dir / "a.ply", dir / "b.ply"}, {});
  expect_the_synthetic_grid(chunks);
  EXPECT_EQ(chunks.valid, whole.valid);
  EXPECT_EQ(chunks.points, whole.points);
  EXPECT_EQ(chunks.times, whole.times);
}

TEST(ProfilerGrid, BandsHoldTheWholeGridsCellsAndEachRepeatsTheLastLineOfTheOneBefore) {
  test::TempDir dir;
  test::write_profiler_lines(dir / "a.ply", 0, 2);
  test::write_profiler_lines(dir / "b.ply", 2, kLines);
  const std::vector<std::filesystem::path> files{dir / "a.ply", dir / "b.ply"};
  const SensorGrid whole = profiler_grid(files, {});
  for (const std::size_t rows : {1, 2, 3, 4, 5, 9}) {  // 1 asks for 2: a band needs a quad's two rows
    std::vector<SensorGrid> bands;
    const ProfilerGridShape shape =
        for_each_profiler_band(files, {}, {0, rows * kBins}, [&](const SensorGrid& band) { bands.push_back(band); });
    EXPECT_EQ(shape.rows, whole.rows);
    EXPECT_EQ(shape.cols, whole.cols);
    EXPECT_EQ(shape.origin, whole.origin);
    // Row by row, the bands (less each one's repeated first row) are the whole grid.
    SensorGrid joined;
    joined.resize(0, whole.cols, false);
    for (std::size_t b = 0; b < bands.size(); ++b) {
      const SensorGrid& band = bands[b];
      ASSERT_LE(band.rows, std::max<std::size_t>(rows, 2)) << rows;
      EXPECT_EQ(band.origin, whole.origin);
      EXPECT_TRUE(band.wrap_columns);
      const std::size_t skip = b == 0 ? 0 : whole.cols;
      if (b > 0) {
        const SensorGrid& before = bands[b - 1];
        const auto last = static_cast<std::ptrdiff_t>(before.index(before.rows - 1, 0));
        EXPECT_TRUE(std::equal(band.points.begin(), band.points.begin() + kBins, before.points.begin() + last));
        EXPECT_TRUE(std::equal(band.valid.begin(), band.valid.begin() + kBins, before.valid.begin() + last));
      }
      const auto from = static_cast<std::ptrdiff_t>(skip);
      joined.points.insert(joined.points.end(), band.points.begin() + from, band.points.end());
      joined.sensors.insert(joined.sensors.end(), band.sensors.begin() + from, band.sensors.end());
      joined.times.insert(joined.times.end(), band.times.begin() + from, band.times.end());
      joined.valid.insert(joined.valid.end(), band.valid.begin() + from, band.valid.end());
    }
    EXPECT_EQ(joined.points, whole.points) << rows;
    EXPECT_EQ(joined.sensors, whole.sensors) << rows;
    EXPECT_EQ(joined.times, whole.times) << rows;
    EXPECT_EQ(joined.valid, whole.valid) << rows;
  }
}

TEST(ProfilerGrid, LastEchoesAreTakenWhenAsked) {
  test::TempDir dir;
  test::write_profiler_lines(dir / "all.ply", 0, kLines);
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
