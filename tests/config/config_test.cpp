// SPDX-License-Identifier: MIT
#include "citymesh/config/config.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "citymesh/core/error.h"
#include "test_support.h"

namespace citymesh {
namespace {

const char* kMinimal = R"(
[project]
crs = "EPSG:2154"
vertical_datum = "ellipsoidal"

[[acquisition]]
path = "b.ply"
time = "2026-03-01T09:00:00+01:00"

[[acquisition]]
path = "sub/a.ply"
time = 2026-01-05T10:00:00Z
name = "january"
)";

class ConfigTest : public ::testing::Test {
 protected:
  void SetUp() override {
    std::filesystem::create_directories(dir_ / "sub");
    test::write_text(dir_ / "b.ply", "");
    test::write_text(dir_ / "sub" / "a.ply", "");
  }
  Config parse(const std::string& text, ConfigLoadParams params = {}) {
    test::write_text(dir_ / "run.toml", text);
    return load_config(dir_ / "run.toml", params);
  }
  test::TempDir dir_;
};

TEST_F(ConfigTest, MinimalFileGetsDefaultsAndResolvesPaths) {
  const Config c = parse(kMinimal);
  ASSERT_EQ(c.acquisitions.size(), 2u);
  // In processing order, by time: the file lists b (March) before a (January).
  EXPECT_EQ(c.acquisitions[0].path, dir_ / "sub" / "a.ply");
  EXPECT_EQ(c.acquisitions[0].name, "january");
  EXPECT_EQ(c.acquisitions[0].listed, 1u);
  EXPECT_EQ(c.acquisitions[1].path, dir_ / "b.ply");
  EXPECT_EQ(c.acquisitions[1].name, "b");
  EXPECT_EQ(c.acquisitions[1].listed, 0u);
  EXPECT_EQ(c.acquisitions[0].time, parse_iso8601("2026-01-05T10:00:00Z", "t"));
  EXPECT_EQ(c.acquisitions[1].time, parse_iso8601("2026-03-01T08:00:00Z", "t"));
  const auto list = c.acquisition_list();
  EXPECT_EQ(list[1].index, 1u);
  EXPECT_EQ(list[1].path, dir_ / "b.ply");
  EXPECT_EQ(c.listed_indices(), (std::vector<std::int32_t>{1, 0}));
  const Config defaults;
  EXPECT_EQ(c.change.distance_threshold, defaults.change.distance_threshold);
  EXPECT_EQ(c.change.sustainability, std::chrono::days(30));
  EXPECT_EQ(c.run.memory, 2ull << 30);
  EXPECT_EQ(c.crs().name(), "RGF93 / Lambert-93");
}

TEST_F(ConfigTest, EveryKeyCanBeSet) {
  const Config c = parse(std::string(kMinimal) + R"(
[input]
sensor_origin = ["ox", "oy", "oz"]
time = ["t"]
intensity = "amplitude"
[change]
distance_threshold = 0.05
conflict_margin = 0.2
empty_space = "nearest-sample"
normal_angle = 30
sustainability = "12h"
[mosaic]
quality = "area"
quality_weight = 2
boundary_weight = 0.25
overlap_weight = 1000
seam_weight = 3
[tiling]
tile_size = 80
halo = 4
origin = [650000, 6860000]
[run]
threads = 2
memory = "512MiB"
[output]
tiles_3d = false
ply = true
draco_tolerance = 0.002
)");
  EXPECT_EQ(c.input.sensor_origin[1], "oy");
  EXPECT_EQ(c.input.time, std::vector<std::string>{"t"});
  EXPECT_EQ(c.ply_read_params().intensity_name, "amplitude");
  EXPECT_EQ(c.change.distance_threshold, 0.05);
  EXPECT_EQ(c.change.sustainability, std::chrono::hours(12));
  EXPECT_EQ(c.change.empty_space, EmptySpaceReach::nearest_sample);
  EXPECT_EQ(c.mosaic.quality, QualityMeasure::area);
  EXPECT_EQ(c.mosaic.overlap_weight, 1000);
  EXPECT_EQ(c.tiling.origin[1], 6860000);
  EXPECT_EQ(c.run.threads, 2u);
  EXPECT_EQ(c.run.memory, 512ull << 20);
  EXPECT_FALSE(c.output.tiles_3d);
  EXPECT_EQ(c.output.draco_tolerance, 0.002);
}

TEST_F(ConfigTest, OverridesWinOverTheFile) {
  ConfigLoadParams params;
  params.overrides = {"change.distance_threshold=0.2", "run.memory=1GiB", "project.crs=EPSG:32631"};
  const Config c = parse(kMinimal, params);
  EXPECT_EQ(c.change.distance_threshold, 0.2);
  EXPECT_EQ(c.run.memory, 1ull << 30);
  EXPECT_EQ(c.project.crs, "EPSG:32631");
  params.overrides = {"change.distanse=1"};
  EXPECT_THROW(parse(kMinimal, params), ConfigError);
  params.overrides = {"no equals sign"};
  EXPECT_THROW(parse(kMinimal, params), UsageError);
}

TEST_F(ConfigTest, DumpedDefaultsParseBackToTheDefaults) {
  // Uncomment the required keys' examples and add an acquisition: the result must equal the
  // default-constructed params, key by key (compared through the effective config text).
  std::string dumped = dump_default_config();
  for (const char* key : {"crs", "vertical_datum"}) {
    const std::string commented = std::string("# ") + key + " = ";
    const auto at = dumped.find(commented);
    ASSERT_NE(at, std::string::npos) << key;
    dumped.erase(at, 2);
  }
  dumped += "\n[[acquisition]]\npath = \"b.ply\"\ntime = \"2026-01-05\"\n";
  const Config c = parse(dumped);
  Config expected = c;
  expected.change = {};
  expected.mosaic = {};
  expected.tiling = {};
  expected.run = {};
  expected.output = {};
  expected.input = {};
  EXPECT_EQ(effective_config_toml(c), effective_config_toml(expected));
}

TEST_F(ConfigTest, EffectiveConfigIsItselfAValidConfig) {
  const Config c = parse(kMinimal);
  const Config again = parse(effective_config_toml(c));
  EXPECT_EQ(effective_config_toml(again).substr(effective_config_toml(again).find('\n')),
            effective_config_toml(c).substr(effective_config_toml(c).find('\n')));
}

TEST_F(ConfigTest, AcquisitionsAreProcessedByTimeTiesInListingOrderAndPrintedAsListed) {
  test::write_text(dir_ / "c.ply", "");
  test::write_text(dir_ / "d.ply", "");
  const Config c = parse(std::string(kMinimal) + R"(
[[acquisition]]
path = "c.ply"
time = 2026-02-01T00:00:00Z

[[acquisition]]
path = "d.ply"
time = "2026-03-01T08:00:00Z"
)");  // d has b's time: neither is newer, and b, listed first, comes first
  std::vector<std::string> names;
  for (const AcquisitionEntry& a : c.acquisitions) names.push_back(a.name);
  EXPECT_EQ(names, (std::vector<std::string>{"january", "c", "b", "d"}));
  EXPECT_EQ(c.listed_indices(), (std::vector<std::int32_t>{1, 2, 0, 3}));
  // As a path value ends: key descriptions name files too (mosaic.ply).
  const auto at = [](const std::string& text, const char* file) { return text.find(fmt::format("/{}\"", file)); };
  const std::string listed = effective_config_toml(c), processing = effective_config_toml(c, TableOrder::processing);
  EXPECT_LT(at(listed, "b.ply"), at(listed, "a.ply"));
  EXPECT_LT(at(listed, "a.ply"), at(listed, "c.ply"));
  EXPECT_LT(at(listed, "c.ply"), at(listed, "d.ply"));
  EXPECT_LT(at(processing, "a.ply"), at(processing, "c.ply"));
  EXPECT_LT(at(processing, "c.ply"), at(processing, "b.ply"));
  EXPECT_LT(at(processing, "b.ply"), at(processing, "d.ply"));
  // Printed as listed, the config reads back to the same places.
  EXPECT_EQ(parse(listed).listed_indices(), c.listed_indices());
}

TEST_F(ConfigTest, AWithdrawnAcquisitionKeepsItsPlaceAndNeedsNoFile) {
  std::filesystem::remove(dir_ / "b.ply");
  const std::string withdrawn = std::string(kMinimal).replace(std::string(kMinimal).find("time = \"2026-03"), 0,
                                                              "withdrawn = true\n");
  const Config c = parse(withdrawn);  // b.ply is gone: it is not read
  ASSERT_EQ(c.acquisitions.size(), 2u);
  EXPECT_FALSE(c.acquisitions[0].withdrawn);
  EXPECT_TRUE(c.acquisitions[1].withdrawn);  // b, in March: still in its place by time
  EXPECT_TRUE(c.acquisition_list()[1].withdrawn);
  EXPECT_EQ(c.acquisitions[1].listed, 0u) << "nor renumbered in the outputs";
  // The effective config says so, and parses back to it.
  EXPECT_NE(effective_config_toml(c).find("withdrawn = true"), std::string::npos);
  EXPECT_TRUE(parse(effective_config_toml(c)).acquisitions[1].withdrawn);
  // A pass listed again (corrected) may name the withdrawn one's file.
  test::write_text(dir_ / "b.ply", "");
  EXPECT_NO_THROW(parse(withdrawn + "\n[[acquisition]]\npath = \"b.ply\"\ntime = 2026-04-01\n"));
  EXPECT_THROW(parse(std::string(kMinimal) + "\n[[acquisition]]\npath = \"b.ply\"\ntime = 2026-04-01\n"), ConfigError);
  // Not a boolean, or every pass withdrawn: refused, naming the key.
  try {
    parse(std::string(kMinimal).replace(std::string(kMinimal).find("time = \"2026-03"), 0, "withdrawn = \"yes\"\n"));
    ADD_FAILURE() << "a string accepted";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("acquisition[0].withdrawn"), std::string::npos) << e.what();
  }
  std::string both = withdrawn;
  both.replace(both.find("name = \"january\""), 0, "withdrawn = true\n");
  EXPECT_THROW(parse(both), ConfigError);
}

TEST(ConfigExamples, CommentedExampleAndDemoParse) {
  const Config example = load_config(test::source_dir() / "configs/example.toml", {.overrides = {}, .check_files = false});
  EXPECT_GE(example.acquisitions.size(), 2u);
  const Config cluster = load_config(test::source_dir() / "configs/cluster.toml", {.overrides = {}, .check_files = false});
  EXPECT_GE(cluster.acquisitions.size(), 2u);
  EXPECT_EQ(cluster.project.work, std::filesystem::path("/shared/citymesh/paris/work"));
  const Config demo = load_config(test::source_dir() / "configs/demo.toml");
  EXPECT_GE(demo.acquisitions.size(), 2u);
}

TEST(ConfigDocs, ReferenceMatchesDumpDefaults) {
  // docs/config-reference.md embeds the output of `citymesh config --dump-defaults` between
  // two markers; this keeps the documentation from drifting from the code.
  const std::string doc = test::read_text(test::source_dir() / "docs/config-reference.md");
  const std::string begin = "<!-- dump-defaults:begin -->\n```toml\n", end = "```\n<!-- dump-defaults:end -->";
  const auto b = doc.find(begin), e = doc.find(end);
  ASSERT_NE(b, std::string::npos);
  ASSERT_NE(e, std::string::npos);
  EXPECT_EQ(doc.substr(b + begin.size(), e - b - begin.size()), dump_default_config())
      << "regenerate with: citymesh config --dump-defaults";
}

}  // namespace
}  // namespace citymesh
