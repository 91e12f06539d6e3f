// SPDX-License-Identifier: MIT
// The web side against real tools: the Khronos glTF validator on every glb of a run, and both
// viewer pages in headless Chromium: three.js (the screenshot must show the street) and
// CesiumJS (every tile loads, none fails, and the tileset stands where the input lies on
// Earth). Skips when the npm packages (tools/setup) or Debian's chromium are missing.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdlib>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "citymesh/encode/glb.h"
#include "citymesh/render/render.h"
#include "mosaic_output.h"
#include "test_support.h"

namespace citymesh {
namespace {

std::filesystem::path web_dir() { return test::source_dir() / "tools" / "web"; }

bool have_npm_packages() {
  return std::system("node --version > /dev/null 2>&1") == 0 &&
         std::filesystem::exists(web_dir() / "node_modules" / "gltf-validator") &&
         std::filesystem::exists(web_dir() / "node_modules" / "playwright-core");
}

/// Simulates a short street and runs every step; returns the output folder.
std::filesystem::path run_short_street(const test::TempDir& tmp) {
  const auto sim = tmp / "sim";
  EXPECT_EQ(test::run_citymesh(fmt::format("simulate --out {} --length 40", sim.string())).exit_code, 0);
  const test::CommandResult run = test::run_citymesh(fmt::format("run {} --no-pictures", (sim / "config.toml").string()));
  EXPECT_EQ(run.exit_code, 0) << run.err;
  return sim / "out";
}

struct Shell {
  int exit_code;
  std::string out;
};

Shell shell(const std::string& command, const test::TempDir& tmp) {
  const auto log = tmp / "shell.log";
  const int status = std::system((command + " > " + log.string() + " 2>&1").c_str());
  return {WIFEXITED(status) ? WEXITSTATUS(status) : 128, test::read_text(log)};
}

TEST(Web, GltfValidatorFindsNoErrorInARunsTiles) {
  if (!have_npm_packages()) GTEST_SKIP() << "npm packages missing: run tools/setup";
  test::TempDir tmp;
  const auto out = run_short_street(tmp);
  const Shell v = shell(fmt::format("node {} {}", (web_dir() / "validate.mjs").string(), (out / "tiles").string()), tmp);
  EXPECT_EQ(v.exit_code, 0) << v.out;
  EXPECT_NE(v.out.find(" 0 errors"), std::string::npos) << v.out;
  const test::CommandResult check = test::run_citymesh(fmt::format("check {}", out.string()));
  EXPECT_EQ(check.exit_code, 0) << check.out;
}

/// `citymesh view` in the background, stopped (SIGINT, as Ctrl-C) when the test ends.
class Viewer {
 public:
  Viewer(const std::filesystem::path& output, const test::TempDir& tmp) : log_(tmp / "view.log") {
    std::filesystem::remove(log_);  // an earlier viewer's address is not this one's
    const std::string command = fmt::format("{} view {} --port 0 > {} 2>&1 & echo $!", CITYMESH_BINARY, output.string(),
                                            log_.string());
    FILE* pipe = ::popen(command.c_str(), "r");
    if (pipe != nullptr && std::fscanf(pipe, "%d", &pid_) != 1) pid_ = -1;
    if (pipe != nullptr) ::pclose(pipe);
  }
  ~Viewer() {
    if (pid_ > 0) ::kill(pid_, SIGINT);
  }
  /// The address it printed, or "" after 20 s.
  std::string url() const {
    for (int i = 0; i < 200; ++i) {
      const std::string text = std::filesystem::exists(log_) ? test::read_text(log_) : "";
      const auto at = text.find("http://127.0.0.1:");
      if (at != std::string::npos) return text.substr(at, text.find('/', at + 7) - at + 1);
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    return "";
  }

 private:
  std::filesystem::path log_;
  int pid_ = -1;
};

/// How much of a screenshot the street covers, and how wide it spans, away from the status
/// and legend lines: every pixel not of the page's background colour (#1b2330) counts.
struct StreetInPicture {
  double covered = 0;        ///< share of the pixels
  std::uint32_t spread = 0;  ///< pixels from the leftmost to the rightmost
};

StreetInPicture street_in(const Image& image) {
  std::size_t drawn = 0;
  std::uint32_t left = image.width, right = 0;
  for (std::uint32_t y = 40; y + 40 < image.height; ++y) {
    for (std::uint32_t x = 0; x < image.width; ++x) {
      const Rgb8 p = image.pixels[std::size_t(y) * image.width + x];
      if (std::abs(p.r - 0x1b) + std::abs(p.g - 0x23) + std::abs(p.b - 0x30) < 30) continue;
      ++drawn;
      left = std::min(left, x);
      right = std::max(right, x);
    }
  }
  return {double(drawn) / double(image.width * (image.height - 80)), right >= left ? right - left : 0};
}

bool have_browser() { return have_npm_packages() && std::filesystem::exists("/usr/bin/chromium"); }

/// A viewer page's screenshot: the page's status line (or the error) and the picture.
struct PageShot {
  Shell shot;
  Image image;
};

/// Serves `out` with `citymesh view`, opens `page` (path and query under its address) in
/// headless Chromium, waits until the page has settled and takes the screenshot; `options`
/// go to screenshot.mjs (e.g. "--click X,Y").
PageShot screenshot(const std::filesystem::path& out, const std::string& page, const test::TempDir& tmp,
                    const std::string& options = "") {
  const Viewer viewer(out, tmp);
  const std::string url = viewer.url();
  EXPECT_FALSE(url.empty()) << "citymesh view printed no address";
  const auto png = tmp / "page.png";
  PageShot s{shell(fmt::format("node {} '{}{}' {} --timeout 120 {}", (web_dir() / "screenshot.mjs").string(), url, page,
                               png.string(), options),
                   tmp),
             {}};
  if (s.shot.exit_code == 0) s.image = read_png(png);
  return s;
}

void expect_street_drawn(const Image& image) {
  const StreetInPicture street = street_in(image);
  EXPECT_GT(street.covered, 0.15) << "the street covers " << street.covered * 100 << " % of the view";
  EXPECT_GT(street.spread, image.width / 2) << "the street spans " << street.spread << " pixels";
}

/// The legend both pages show for the run of `config`: each acquisition's name and day, in
/// the order of the tables (the swatches hold no text), then the stitch entry.
std::string expected_legend(const std::filesystem::path& config) {
  const std::string text = test::read_text(config);
  std::vector<std::string> names, days;
  std::istringstream lines(text);
  for (std::string line; std::getline(lines, line);) {
    const auto quoted = [&] { return line.substr(line.find('"') + 1, line.rfind('"') - line.find('"') - 1); };
    if (line.starts_with("name = ")) names.push_back(quoted());
    if (line.starts_with("time = ")) days.push_back(quoted().substr(0, 10));
  }
  EXPECT_EQ(names.size(), days.size());
  std::string legend = "legend: ";
  for (std::size_t k = 0; k < std::min(names.size(), days.size()); ++k) legend += names[k] + " (" + days[k] + ")";
  return legend + "stitch";
}

/// The share of the picture whose pixels `is` accepts (the status and legend lines left out).
template <class Predicate>
double share_of(const Image& image, Predicate is) {
  std::size_t n = 0;
  for (std::uint32_t y = 40; y + 40 < image.height; ++y) {
    for (std::uint32_t x = 0; x < image.width; ++x) n += is(image.pixels[std::size_t(y) * image.width + x]) ? 1 : 0;
  }
  return double(n) / double(image.width * (image.height - 80));
}

/// A pixel's hue in degrees [0, 360) when it is saturated and bright enough to have one
/// (saturation above `min_saturation`, value above 0.3), else -1.
double hue_of(Rgb8 p, double min_saturation = 0.45) {
  const int hi = std::max({p.r, p.g, p.b}), lo = std::min({p.r, p.g, p.b}), range = hi - lo;
  if (hi < 77 || range <= min_saturation * hi) return -1;
  double h = hi == p.r ? double(p.g - p.b) / range : hi == p.g ? 2.0 + double(p.b - p.r) / range
                                                                : 4.0 + double(p.r - p.g) / range;
  return std::fmod(h * 60.0 + 360.0, 360.0);
}

// Hues that survive the pages' lighting (measured on both pages: shading and CesiumJS's sRGB
// output move them by ten degrees at most): the palette's orange (acquisition 1, 255 127 14,
// 28 degrees) shows at 30-39 degrees; the date ramp has no colour there, and its newest end
// (253 231 37, 54 degrees) shows at 50-59.
bool orange(Rgb8 p) { return hue_of(p) >= 20 && hue_of(p) < 45; }
bool yellow(Rgb8 p) { return hue_of(p) >= 48 && hue_of(p) < 66; }

/// Where the tests click: below the middle of the picture, on the street in both pages' views.
constexpr std::uint32_t kClickX = 512, kClickY = 400;

/// After a click at (kClickX, kClickY): the page named the pass of the triangle there (as the
/// config names it) or a stitch triangle, and the pixel shows that pass's colour of citymesh's
/// pictures (source_color; hues within 15 degrees, when the colour has a clear one: not the
/// palette's brown or grey, which the pages' shading leaves without).
void expect_click_names_the_pass(const PageShot& page) {
  const std::string& out = page.shot.out;
  const auto at = out.find("picked: ");
  ASSERT_NE(at, std::string::npos) << out;
  int acquisition = -1;
  if (out.compare(at + 8, 18, "a stitch triangle ") != 0) {
    const auto index = out.find("(acquisition ", at);
    ASSERT_NE(index, std::string::npos) << out;
    ASSERT_EQ(std::sscanf(out.c_str() + index, "(acquisition %d)", &acquisition), 1) << out;
    EXPECT_EQ(out.compare(at + 8, fmt::format("epoch {},", acquisition).size(), fmt::format("epoch {},", acquisition)),
              0)
        << out;
  }
  const double expected = hue_of(app::source_color(acquisition), 0.6);
  const double seen = hue_of(page.image.pixels[std::size_t(kClickY) * page.image.width + kClickX]);
  if (expected >= 0) {
    const double apart = std::abs(std::fmod(seen - expected + 540.0, 360.0) - 180.0);
    EXPECT_LE(apart, 15.0) << "hue " << seen << " at the click, " << expected << " for " << out.substr(at);
  }
}

TEST(Web, ViewerDrawsTheStreetInHeadlessChromium) {
  if (!have_browser()) GTEST_SKIP() << "npm packages (tools/setup) or Debian's chromium missing";
  test::TempDir tmp;
  const auto out = run_short_street(tmp);
  const PageShot page = screenshot(out, "", tmp, fmt::format("--click {},{}", kClickX, kClickY));
  ASSERT_EQ(page.shot.exit_code, 0) << page.shot.out;
  expect_click_names_the_pass(page);
  EXPECT_NE(page.shot.out.find("tiles loaded"), std::string::npos) << page.shot.out;
  EXPECT_NE(page.shot.out.find(expected_legend(out.parent_path() / "config.toml")), std::string::npos) << page.shot.out;
  expect_street_drawn(page.image);
  EXPECT_GT(share_of(page.image, orange), 0.01) << "acquisition 1's orange";
}

/// Where the input lies: latitude, longitude and ellipsoidal height bounds over every
/// acquisition, as `citymesh info --config --json` gives them (GeographicLib, not the tileset).
struct Place {
  double lat[2] = {90, -90}, lon[2] = {180, -180}, height[2] = {1e9, -1e9};
};

Place input_place(const std::filesystem::path& config, double geoid_undulation) {
  const test::CommandResult info = test::run_citymesh(fmt::format("info --config {} --json", config.string()));
  EXPECT_EQ(info.exit_code, 0) << info.err;
  Place p;
  std::istringstream lines(info.out);
  for (std::string line; std::getline(lines, line);) {
    const auto j = nlohmann::json::parse(line);
    const auto& ll = j.at("lat_lon_bounds");
    p.lat[0] = std::min(p.lat[0], ll.at("lat")[0].get<double>());
    p.lat[1] = std::max(p.lat[1], ll.at("lat")[1].get<double>());
    p.lon[0] = std::min(p.lon[0], ll.at("lon")[0].get<double>());
    p.lon[1] = std::max(p.lon[1], ll.at("lon")[1].get<double>());
    p.height[0] = std::min(p.height[0], j.at("bounds").at("min")[2].get<double>() + geoid_undulation);
    p.height[1] = std::max(p.height[1], j.at("bounds").at("max")[2].get<double>() + geoid_undulation);
  }
  return p;
}

TEST(Web, CesiumJsLoadsEveryTileWhereTheInputLies) {
  if (!have_browser()) GTEST_SKIP() << "npm packages (tools/setup) or Debian's chromium missing";
  test::TempDir tmp;
  const auto out = run_short_street(tmp);
  // A screen-space error of 0 asks for the finest tiles: every tile of the tree is loaded.
  const PageShot page = screenshot(out, "cesium.html?error=0", tmp, fmt::format("--click {},{}", kClickX, kClickY));
  const Shell& shot = page.shot;
  ASSERT_EQ(shot.exit_code, 0) << shot.out;
  expect_click_names_the_pass(page);
  const std::string tileset = test::read_text(out / "tiles" / "tileset.json");
  std::size_t tiles = 0;
  for (auto at = tileset.find("\"uri\""); at != std::string::npos; at = tileset.find("\"uri\"", at + 1)) ++tiles;
  ASSERT_GT(tiles, 1u);
  EXPECT_NE(shot.out.find(fmt::format(" {} tiles loaded, 0 failed", tiles)), std::string::npos) << shot.out;

  // The simulator writes Lambert-93 with orthometric heights: ellipsoidal = z + undulation.
  const auto config = out.parent_path() / "config.toml";
  const std::string text = test::read_text(config);
  const auto undulation_at = text.find("geoid_undulation = ");
  ASSERT_NE(undulation_at, std::string::npos) << text;
  const Place input = input_place(config, std::stod(text.substr(undulation_at + 19)));
  double lat = 0, lon = 0, height = 0;
  const auto at = shot.out.find("centre lat ");
  ASSERT_NE(at, std::string::npos) << shot.out;
  ASSERT_EQ(std::sscanf(shot.out.c_str() + at, "centre lat %lf lon %lf h %lf", &lat, &lon, &height), 3) << shot.out;
  EXPECT_GE(lat, input.lat[0]);
  EXPECT_LE(lat, input.lat[1]);
  EXPECT_GE(lon, input.lon[0]);
  EXPECT_LE(lon, input.lon[1]);
  EXPECT_GE(height, input.height[0]);
  EXPECT_LE(height, input.height[1]);

  EXPECT_NE(shot.out.find(expected_legend(config)), std::string::npos) << shot.out;
  expect_street_drawn(page.image);
  EXPECT_GT(share_of(page.image, orange), 0.01) << "acquisition 1's orange";
}

TEST(Web, BothPagesColourByDateFromTheTilesMetadata) {
  if (!have_browser()) GTEST_SKIP() << "npm packages (tools/setup) or Debian's chromium missing";
  test::TempDir tmp;
  const auto out = run_short_street(tmp);
  for (const std::string page_url : {"?color=date", "cesium.html?color=date"}) {
    const PageShot page = screenshot(out, page_url, tmp);
    ASSERT_EQ(page.shot.exit_code, 0) << page_url << ": " << page.shot.out;
    EXPECT_NE(page.shot.out.find(expected_legend(out.parent_path() / "config.toml")), std::string::npos)
        << page.shot.out;
    expect_street_drawn(page.image);
    // The palette's orange is gone (its pages show it above), the newest passes' yellow is there.
    EXPECT_LT(share_of(page.image, orange), 0.001) << page_url;
    EXPECT_GT(share_of(page.image, yellow), 0.002) << page_url;
  }
}

/// Adds to the tileset of `tiles` a leaf as the export writes a tile whose triangles all come
/// from stitching: every feature id null, so write_glb gives it no feature ids at all.
void add_stitch_only_tile(const std::filesystem::path& tiles) {
  const std::vector<Vec3f> positions{{0, 0, 0}, {8, 0, 0}, {0, 8, 0}};  // east-north-up, by the root's origin
  const std::vector<Triangle> triangles{{0, 1, 2}};
  const std::vector<std::uint16_t> ids(positions.size(), 65535);
  GlbParams params;
  params.acquisitions = {{"epoch 0", "2026-01-05T10:00:00Z"}};
  const std::vector<std::uint8_t> glb = write_glb({positions, triangles, ids, {}, {}}, params);
  test::write_text(tiles / "stitch_only.glb", std::string(glb.begin(), glb.end()));
  nlohmann::json tileset = nlohmann::json::parse(test::read_text(tiles / "tileset.json"));
  tileset["root"]["children"].push_back({{"boundingVolume", {{"box", {4, 4, 0, 4, 0, 0, 0, 4, 0, 0, 0, 1}}}},
                                         {"content", {{"uri", "stitch_only.glb"}}},
                                         {"geometricError", 0.0},
                                         {"refine", "REPLACE"}});
  test::write_text(tiles / "tileset.json", tileset.dump(1));
}

TEST(Web, CesiumJsDrawsATileOfStitchTrianglesOnly) {
  if (!have_browser()) GTEST_SKIP() << "npm packages (tools/setup) or Debian's chromium missing";
  test::TempDir tmp;
  const auto out = run_short_street(tmp);
  add_stitch_only_tile(out / "tiles");
  // The page's colouring reads the feature ids, which such a tile lacks: before session 66's
  // guard its shader did not compile ("no such field in structure") and nothing was drawn.
  const PageShot page = screenshot(out, "cesium.html?error=0", tmp);
  ASSERT_EQ(page.shot.exit_code, 0) << page.shot.out;
  EXPECT_EQ(page.shot.out.find("console error"), std::string::npos) << page.shot.out;
  EXPECT_NE(page.shot.out.find(" 0 failed"), std::string::npos) << page.shot.out;
  expect_street_drawn(page.image);
  EXPECT_GT(share_of(page.image, [](Rgb8 p) { return p.r > 150 && p.b > 150 && p.g < 60; }), 0.0005)
      << "the stitch tile's magenta";
}

}  // namespace
}  // namespace citymesh
