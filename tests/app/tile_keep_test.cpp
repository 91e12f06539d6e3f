// SPDX-License-Identifier: MIT
// A tile's result is kept when a neighbour was redone, only when it is still right: the same
// inputs and the same decisions of the neighbours on the tile's halo (on a finished run's
// tiles and results).
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <optional>
#include <set>
#include <utility>
#include <vector>

#include "citymesh/tiler/tiler.h"
#include "test_support.h"
#include "tile_job.h"
#include "tile_plan.h"

namespace citymesh {
namespace {

/// The labels of a finished result, whatever digest it was written under.
std::vector<app::OwnedLabel> labels_of(const std::filesystem::path& file, const TileStore& store) {
  const std::optional<app::ResultOrigin> origin = app::tile_result_origin(file);
  if (!origin) return {};
  return app::read_tile_labels(file, origin->result, store).value_or(std::vector<app::OwnedLabel>{});
}

TEST(TileKeep, AResultIsKeptAfterANeighbourOnlyForTheSameInputsAndTheSameDecisionsOnItsHalo) {
  test::TempDir dir;
  const std::string sim = (dir / "sim").string();
  ASSERT_EQ(test::run_citymesh(fmt::format("simulate --out {} --length 30", sim)).exit_code, 0);
  const auto run = test::run_citymesh(
      fmt::format("run {}/config.toml --no-pictures --set tiling.tile_size=10 --set output.labels=false", sim));
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const std::optional<TileStore> store = read_tile_manifest(dir / "sim/work/tiles");
  ASSERT_TRUE(store.has_value());
  const auto result_file = [&](TileKey key) { return dir / "sim/work/results" / (key.name() + ".bin"); };
  // A tile of the last phase: its neighbours' labels, and one of them on its halo, one not.
  std::size_t checked = 0;
  for (std::size_t k = 0; k < store->tiles.size(); ++k) {
    const TileKey key = store->tiles[k].key;
    if (app::tile_phase(key) != app::kTilePhases - 1) continue;
    std::vector<std::vector<app::OwnedLabel>> neighbours;
    for (const std::size_t d : app::tile_dependencies(*store, k)) {
      neighbours.push_back(labels_of(result_file(store->tiles[d].key), *store));
    }
    std::set<std::pair<std::uint32_t, std::uint32_t>> halo;
    const std::vector<TilePiece> pieces = read_tile(*store, key);
    for (std::uint32_t a = 0; a < pieces.size(); ++a) {
      for (std::size_t t = 0; t < pieces[a].roles.size(); ++t) {
        if (pieces[a].roles[t] == TileRole::halo) halo.insert({a, pieces[a].triangle_index[t]});
      }
    }
    // (neighbour, label) of a triangle on the halo and of one elsewhere.
    std::optional<std::pair<std::size_t, std::size_t>> on_halo, elsewhere;
    for (std::size_t n = 0; n < neighbours.size(); ++n) {
      for (std::size_t l = 0; l < neighbours[n].size(); ++l) {
        const bool in_halo = halo.contains({neighbours[n][l].acquisition, neighbours[n][l].index});
        (in_halo ? on_halo : elsewhere) = std::pair{n, l};
      }
    }
    if (!on_halo || !elsewhere) continue;
    const auto settled_with = [&](std::optional<std::pair<std::size_t, std::size_t>> flipped) {
      app::SettledSelection settled;
      for (std::size_t n = 0; n < neighbours.size(); ++n) {
        std::vector<app::OwnedLabel> labels = neighbours[n];
        if (flipped && flipped->first == n) labels[flipped->second].selected ^= 1;
        settled.add(labels);
      }
      return settled;
    };
    const std::filesystem::path file = result_file(key);
    const std::optional<app::ResultOrigin> origin = app::tile_result_origin(file);
    ASSERT_TRUE(origin.has_value()) << key.name();
    const std::vector<app::OwnedLabel> before = labels_of(file, *store);
    // What the tile job recorded is what the neighbours' results say of its halo.
    EXPECT_EQ(app::tile_settled_fingerprint(*store, key, settled_with(std::nullopt)), origin->settled) << key.name();
    const std::uint64_t next = origin->result + 1;
    EXPECT_FALSE(app::keep_if_still_right(file, *store, key, {next, origin->inputs + 1}, settled_with(std::nullopt)))
        << "other inputs";
    EXPECT_FALSE(app::keep_if_still_right(file, *store, key, {next, origin->inputs}, settled_with(on_halo)))
        << "another decision on the halo";
    EXPECT_TRUE(app::tile_result_is_finished(file, origin->result, *store)) << "left as it was";
    EXPECT_TRUE(app::keep_if_still_right(file, *store, key, {next, origin->inputs}, settled_with(elsewhere)))
        << "another decision away from the tile";
    EXPECT_TRUE(app::tile_result_is_finished(file, next, *store));
    EXPECT_FALSE(app::tile_result_is_finished(file, origin->result, *store));
    const std::vector<app::OwnedLabel> after = labels_of(file, *store);
    ASSERT_EQ(after.size(), before.size());
    EXPECT_TRUE(std::equal(before.begin(), before.end(), after.begin(),
                           [](const auto& x, const auto& y) { return std::memcmp(&x, &y, sizeof x) == 0; }));
    ++checked;
  }
  EXPECT_GT(checked, 0u);
}

}  // namespace
}  // namespace citymesh
