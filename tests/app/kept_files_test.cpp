// SPDX-License-Identifier: MIT
// The export's caches in files: what is kept is found as it was, a damaged or foreign file is
// made again, and pruning removes only what no run used since.
#include "kept_files.h"

#include <gtest/gtest.h>

#include <chrono>
#include <fstream>

#include "test_support.h"

namespace citymesh::app {
namespace {

SimplifiedMesh simplified() { return {{{0, 1, 2}, {2, 1, 3}, {4, 5, 6}}, 0.012345678901234567}; }

std::vector<std::filesystem::path> files_in(const std::filesystem::path& dir) {
  std::vector<std::filesystem::path> out;
  for (const auto& e : std::filesystem::directory_iterator(dir)) out.push_back(e.path());
  std::sort(out.begin(), out.end());
  return out;
}

TEST(ExportCaches, SimplifiedMeshesAreFoundAsKeptAndDamagedOnesMadeAgain) {
  test::TempDir tmp;
  ExportCaches caches(tmp.path());
  EXPECT_FALSE(caches.simplified.find(7).has_value());
  caches.simplified.keep(7, simplified());
  const std::optional<SimplifiedMesh> found = caches.simplified.find(7);
  ASSERT_TRUE(found.has_value());
  EXPECT_EQ(found->triangles, simplified().triangles);
  EXPECT_EQ(found->error, simplified().error) << "the error to the bit: it goes into tileset.json";
  EXPECT_FALSE(caches.simplified.find(8).has_value());
  EXPECT_FALSE(caches.primitives.find(7).has_value()) << "another kind under the same digest";

  const std::vector<std::filesystem::path> files = files_in(export_cache_folder(tmp.path()));
  ASSERT_EQ(files.size(), 1u);
  EXPECT_EQ(files[0].extension(), ".simp");
  {
    std::fstream f(files[0], std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(-2, std::ios::end);
    f.put('\x7f');
  }
  EXPECT_FALSE(caches.simplified.find(7).has_value()) << "a damaged file is not taken";
}

TEST(ExportCaches, PruningRemovesWhatNoRunUsedSinceOfEitherKind) {
  test::TempDir tmp;
  ExportCaches caches(tmp.path());
  caches.simplified.keep(1, simplified());
  caches.simplified.keep(2, simplified());
  caches.primitives.keep(3, {nlohmann::json::object(), nlohmann::json::array(), {1, 2, 3}});
  caches.primitives.keep(4, {nlohmann::json::object(), nlohmann::json::array(), {4, 5}});
  // Everything written an hour ago; 2 and 4 then used by this run.
  const auto hour_ago = std::filesystem::file_time_type::clock::now() - std::chrono::hours(1);
  for (const auto& f : files_in(export_cache_folder(tmp.path()))) std::filesystem::last_write_time(f, hour_ago);
  const auto started = std::filesystem::file_time_type::clock::now();
  ASSERT_TRUE(caches.simplified.find(2).has_value());
  ASSERT_TRUE(caches.primitives.find(4).has_value());
  caches.prune(started);
  EXPECT_FALSE(caches.simplified.find(1).has_value());
  EXPECT_TRUE(caches.simplified.find(2).has_value());
  EXPECT_FALSE(caches.primitives.find(3).has_value());
  const std::optional<GlbPrimitive> kept = caches.primitives.find(4);
  ASSERT_TRUE(kept.has_value());
  EXPECT_EQ(kept->draco, (std::vector<std::uint8_t>{4, 5}));
  EXPECT_EQ(files_in(export_cache_folder(tmp.path())).size(), 2u);
}

}  // namespace
}  // namespace citymesh::app
