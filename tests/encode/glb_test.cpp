// SPDX-License-Identifier: MIT
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>

#include "citymesh/core/error.h"
#include "citymesh/encode/glb.h"
#include "grid_triangles.h"

namespace citymesh {
namespace {

/// A wavy n x n grid with one feature id per column band and an intensity per vertex.
struct Tile {
  std::vector<Vec3f> positions;
  std::vector<Triangle> triangles;
  std::vector<std::uint16_t> features;
  std::vector<float> intensities;
  std::vector<Rgb8> colors;
};

Tile tile(int n) {
  Tile t;
  for (int i = 0; i <= n; ++i) {
    for (int j = 0; j <= n; ++j) {
      t.positions.push_back({0.5f * float(i), 0.5f * float(j), 0.2f * std::sin(0.7f * float(i + 2 * j))});
      t.features.push_back(i < n / 2 ? 1 : (i == n ? kNullFeatureId : 3));
      t.intensities.push_back(float(i * 100 + j));
      t.colors.push_back({static_cast<std::uint8_t>(i * 7), static_cast<std::uint8_t>(j * 5), 200});
    }
  }
  t.triangles = test::grid_triangles(n);
  return t;
}

GlbParams params(bool draco) {
  GlbParams p;
  p.draco = draco;
  p.draco_params.position_bits = 16;
  p.draco_params.lattice = DracoLattice{{-1.f, -1.f, -1.f}, 16.f};
  p.acquisitions = {{"a", "2026-01-01T00:00:00Z"}, {"b", "2026-02-01T00:00:00Z"}, {"c", "2026-03-01T00:00:00Z"},
                    {"d", "2026-04-01T00:00:00Z"}};
  return p;
}

/// For every decoded vertex, the original vertex nearest to it (brute force).
std::vector<std::size_t> match(const std::vector<Vec3f>& original, const std::vector<Vec3f>& decoded) {
  std::vector<std::size_t> out;
  for (const Vec3f& d : decoded) {
    std::size_t best = 0;
    for (std::size_t v = 1; v < original.size(); ++v) {
      if (norm(Vec3d(original[v] - d)) < norm(Vec3d(original[best] - d))) best = v;
    }
    out.push_back(best);
  }
  return out;
}

void expect_round_trip(bool draco) {
  const Tile t = tile(16);
  const std::vector<std::uint8_t> bytes =
      write_glb({t.positions, t.triangles, t.features, t.intensities, t.colors}, params(draco));
  const GlbFile glb = parse_glb(bytes, "tile.glb");
  const DecodedMesh m = read_glb_mesh(glb, "tile.glb");
  ASSERT_EQ(m.triangles.size(), t.triangles.size());
  ASSERT_EQ(m.feature_ids.size(), m.positions.size());
  ASSERT_EQ(m.intensities.size(), m.positions.size());
  ASSERT_EQ(m.colors.size(), m.positions.size());
  const double step = 16.0 / double((1 << 16) - 1);
  const std::vector<std::size_t> nearest = match(t.positions, m.positions);
  for (std::size_t v = 0; v < m.positions.size(); ++v) {
    const std::size_t o = nearest[v];
    EXPECT_LE(norm(Vec3d(m.positions[v] - t.positions[o])), draco ? step : 0.0) << v;
    EXPECT_EQ(m.feature_ids[v], t.features[o]) << v;
    EXPECT_EQ(m.intensities[v], t.intensities[o]) << v;
    EXPECT_TRUE(m.colors[v] == t.colors[o]) << v;
  }
  // The glTF side: Draco required, bounds of the decoded positions, the acquisition table.
  const nlohmann::json& j = glb.json;
  EXPECT_EQ(j.contains("extensionsRequired"), draco);
  const nlohmann::json& position = j["accessors"][j["meshes"][0]["primitives"][0]["attributes"]["POSITION"].get<int>()];
  EXPECT_EQ(position["count"].get<std::size_t>(), m.positions.size());
  for (const Vec3f& p : m.positions) {
    for (int k = 0; k < 3; ++k) {
      EXPECT_GE(p[k], position["min"][static_cast<std::size_t>(k)].get<float>());
      EXPECT_LE(p[k], position["max"][static_cast<std::size_t>(k)].get<float>());
    }
  }
  const nlohmann::json& ids = j["meshes"][0]["primitives"][0]["extensions"]["EXT_mesh_features"]["featureIds"][0];
  EXPECT_EQ(ids["featureCount"], 2);  // acquisitions 1 and 3; the null id does not count
  EXPECT_EQ(ids["nullFeatureId"], kNullFeatureId);
  EXPECT_EQ(j["extensions"]["EXT_structural_metadata"]["propertyTables"][0]["count"], 4);
  EXPECT_EQ(j["nodes"][0]["matrix"][6], -1);  // y <- z, z <- -y: glTF's y-up
}

TEST(Glb, DracoRoundTripKeepsTrianglesPositionsAndAttributes) { expect_round_trip(true); }
TEST(Glb, PlainRoundTripIsExact) { expect_round_trip(false); }

TEST(Glb, ATileOfStitchTrianglesOnlyHasNoFeatureIds) {
  // Every vertex of no acquisition (a tile at the edge of a city holding a few triangles that
  // stitching made): no feature id attribute and no metadata, rather than ids with no table.
  Tile t = tile(4);
  std::fill(t.features.begin(), t.features.end(), kNullFeatureId);
  for (const bool draco : {false, true}) {
    const std::vector<std::uint8_t> bytes =
        write_glb({t.positions, t.triangles, t.features, t.intensities, t.colors}, params(draco));
    const GlbFile glb = parse_glb(bytes, "stitch.glb");
    const DecodedMesh m = read_glb_mesh(glb, "stitch.glb");
    EXPECT_TRUE(m.feature_ids.empty());
    EXPECT_EQ(m.triangles.size(), t.triangles.size());
    EXPECT_EQ(m.intensities.size(), m.positions.size());
    EXPECT_FALSE(glb.json.contains("extensions"));
    EXPECT_FALSE(glb.json["meshes"][0]["primitives"][0]["attributes"].contains("_FEATURE_ID_0"));
  }
}

TEST(Glb, ChunksAreFourByteAlignedAndLengthsAgree) {
  const Tile t = tile(4);
  const auto bytes = write_glb({t.positions, t.triangles, t.features, {}, {}}, params(true));
  EXPECT_EQ(bytes.size() % 4, 0u);
  const std::uint32_t json_length = bytes[12] | (bytes[13] << 8) | (bytes[14] << 16) | (bytes[15] << 24);
  EXPECT_EQ(json_length % 4, 0u);
  EXPECT_EQ(parse_glb(bytes, "x").bin.size() % 4, 0u);
}

TEST(Glb, BadFilesAreInputErrorsNamingTheFile) {
  const Tile t = tile(4);
  std::vector<std::uint8_t> bytes = write_glb({t.positions, t.triangles, {}, {}, {}}, params(true));
  auto message = [](std::vector<std::uint8_t> b) {
    try {
      read_glb_mesh(parse_glb(b, "bad.glb"), "bad.glb");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  std::vector<std::uint8_t> truncated(bytes.begin(), bytes.end() - 10);
  EXPECT_NE(message(truncated).find("bad.glb"), std::string::npos);
  std::vector<std::uint8_t> magic = bytes;
  magic[0] = 'x';
  EXPECT_NE(message(magic).find("magic"), std::string::npos);
  std::vector<std::uint8_t> corrupt = bytes;
  const std::string draco = "DRACO";
  const auto at = std::search(corrupt.begin(), corrupt.end(), draco.begin(), draco.end());
  ASSERT_NE(at, corrupt.end());
  at[5] = 99;  // the Draco version
  EXPECT_NE(message(corrupt).find("bad.glb: draco"), std::string::npos) << message(corrupt);
  EXPECT_NE(message({}).find("shorter than a glb header"), std::string::npos);
}

TEST(Glb, InconsistentMeshIsRefused) {
  Tile t = tile(4);
  t.features.pop_back();
  EXPECT_THROW(write_glb({t.positions, t.triangles, t.features, {}, {}}, params(true)), ProcessingError);
}

}  // namespace
}  // namespace citymesh
