// SPDX-License-Identifier: MIT
// The web side against real tools: the Khronos glTF validator on every glb of a run, and the
// viewer page in headless Chromium (the screenshot must show the street). Skips when the npm
// packages (tools/setup) or Debian's chromium are missing.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <chrono>
#include <csignal>
#include <cstdlib>
#include <thread>

#include "citymesh/render/render.h"
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

TEST(Web, ViewerDrawsTheStreetInHeadlessChromium) {
  if (!have_npm_packages()) GTEST_SKIP() << "npm packages missing: run tools/setup";
  if (!std::filesystem::exists("/usr/bin/chromium")) GTEST_SKIP() << "Debian's chromium is not installed";
  test::TempDir tmp;
  const auto out = run_short_street(tmp);
  const Viewer viewer(out, tmp);
  const std::string url = viewer.url();
  ASSERT_FALSE(url.empty()) << "citymesh view printed no address";
  const auto png = tmp / "viewer.png";
  const Shell shot = shell(fmt::format("node {} {} {} --timeout 90", (web_dir() / "screenshot.mjs").string(), url,
                                       png.string()), tmp);
  ASSERT_EQ(shot.exit_code, 0) << shot.out;
  EXPECT_NE(shot.out.find("tiles loaded"), std::string::npos) << shot.out;
  // The background is #1b2330; the street must cover a good part of the picture, across it.
  const Image image = read_png(png);
  std::size_t drawn = 0;
  std::uint32_t left = image.width, right = 0;
  for (std::uint32_t y = 40; y + 40 < image.height; ++y) {  // skip the status and legend lines
    for (std::uint32_t x = 0; x < image.width; ++x) {
      const Rgb8 p = image.pixels[std::size_t(y) * image.width + x];
      if (std::abs(p.r - 0x1b) + std::abs(p.g - 0x23) + std::abs(p.b - 0x30) < 30) continue;
      ++drawn;
      left = std::min(left, x);
      right = std::max(right, x);
    }
  }
  const double covered = double(drawn) / double(image.width * (image.height - 80));
  EXPECT_GT(covered, 0.15) << "the street covers " << covered * 100 << " % of the view";
  EXPECT_GT(right - left, image.width / 2) << "the street spans " << right - left << " pixels";
}

}  // namespace
}  // namespace citymesh
