// SPDX-License-Identifier: MIT
// Reads the real samples in ../shared/data/real when they are there; skips otherwise.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include "citymesh/io/ply_inspect.h"
#include "test_support.h"

namespace citymesh {
namespace {

std::filesystem::path real(const std::string& relative) {
  const auto dir = test::real_data_dir();
  return dir.empty() ? dir : dir / relative;
}

TEST(RealData, StereopolisRieglChunksAreParisLambert93) {
  for (int chunk = 1; chunk <= 5; ++chunk) {
    const auto path = real(fmt::format("terramobilita_riegl_paris2013/sample_riegl_18_0{}.ply", chunk));
    if (path.empty() || !std::filesystem::exists(path)) GTEST_SKIP() << "real data absent";
    const PlyInspection r = inspect_ply(path);
    EXPECT_EQ(r.header.format, PlyFormat::binary_big_endian);
    EXPECT_EQ(r.stats.vertices, 30000u);
    EXPECT_TRUE(r.layout.has_sensor_origin);
    EXPECT_EQ(r.layout.time_name, "GPS_time");
    EXPECT_EQ(r.header.offset, (Vec3d{649000, 6840000, 0}));
    // Paris 6th arrondissement in Lambert-93; the van moves ~3.6 m over the five chunks.
    EXPECT_NEAR((r.bounds.min.x + r.bounds.max.x) / 2, 651070, 60);
    EXPECT_NEAR((r.bounds.min.y + r.bounds.max.y) / 2, 6860760, 150);
    EXPECT_GT(r.time_min, 54160.29);
    EXPECT_LT(r.time_max, 54160.97);
  }
}

TEST(RealData, OusterFramesHaveTheirFullGrid) {
  for (int frame : {1795, 1796, 1797}) {
    const auto path = real(fmt::format("ouster_os1_128_walk3/ouster_os1_128_frame{}.ply", frame));
    if (path.empty() || !std::filesystem::exists(path)) GTEST_SKIP() << "real data absent";
    const PlyInspection r = inspect_ply(path);
    EXPECT_EQ(r.stats.vertices, 128u * 1024u);
    EXPECT_TRUE(r.layout.has_sensor_origin);
    EXPECT_EQ(r.header.find("vertex")->find("ring")->type, PlyScalar::uint8);
  }
}

}  // namespace
}  // namespace citymesh
