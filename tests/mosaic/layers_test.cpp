// SPDX-License-Identifier: MIT
// One layer per pass: a pass whose file holds two overlapping sheets (two turns of a spinning
// scanner) gives the output one of them.
#include <gtest/gtest.h>

#include <chrono>

#include "citymesh/mosaic/mosaic.h"
#include "grid_triangles.h"

namespace citymesh {
namespace {

/// Two 4 x 4 grids of 0.25 m over the same square, 1 cm apart, in one mesh (no shared
/// vertex): triangle t of the first turn and 32 + t of the second overlap.
Mesh two_turns() {
  Mesh m = test::placed_grid(4, 4, [](int i, int j) { return Vec3f{0.25f * float(i), 0.25f * float(j), 0}; });
  const Mesh second = test::placed_grid(4, 4, [](int i, int j) {
    return Vec3f{0.25f * float(i), 0.25f * float(j), 0.01f};
  });
  const auto offset = static_cast<std::uint32_t>(m.positions.size());
  m.positions.insert(m.positions.end(), second.positions.begin(), second.positions.end());
  for (const Triangle& t : second.triangles) m.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
  m.triangle_ids.resize(m.triangles.size());
  return m;
}

struct TwoTurns {
  std::vector<Mesh> meshes{two_turns()};
  std::vector<TimePoint> dates{TimePoint(std::chrono::days(1))};
  ChangeResult change;
  TwoTurns() {
    change.index.offsets = {0, 64};
    change.kept.assign(64, 1);
    std::vector<TrianglePair> pairs;
    for (std::uint32_t t = 0; t < 32; ++t) pairs.emplace_back(t, 32 + t);
    change.layer_pairs = std::move(pairs);
  }
};

TEST(OneLayerPerPass, TheMosaicKeepsTheFirstTurnAndDropsTheSecond) {
  const TwoTurns f;
  MosaicParams params;
  params.fill_holes = false;
  const MosaicSelection s = select_mosaic({f.meshes, f.dates, &f.change, 0.1, {}}, params);
  for (std::uint32_t t = 0; t < 32; ++t) {
    EXPECT_EQ(s.selected[t], 1) << t;
    EXPECT_EQ(s.selected[32 + t], 0) << t << ": a second layer of the pass";
  }
  EXPECT_EQ(s.stats.layers_dropped, 32u);
}

TEST(OneLayerPerPass, AForcedSecondLayerStaysAndItsFirstLayerPartnerGoes) {
  const TwoTurns f;
  std::vector<std::uint8_t> forced(64, 0);
  for (std::uint32_t t = 0; t < 32; t += 4) forced[32 + t] = 1;  // a neighbouring tile's decisions
  forced[0] = 1;                                                 // both of pair 0 forced: both stay
  MosaicParams params;
  params.fill_holes = false;
  const MosaicSelection s = select_mosaic({f.meshes, f.dates, &f.change, 0.1, forced}, params);
  for (std::uint32_t t = 0; t < 32; ++t) {
    const bool second_forced = forced[32 + t] != 0;
    EXPECT_EQ(s.selected[32 + t], second_forced ? 1 : 0) << t;
    EXPECT_EQ(s.selected[t], !second_forced || t == 0 ? 1 : 0) << t;
  }
  EXPECT_EQ(s.stats.layers_dropped, 31u);
}

TEST(OneLayerPerPass, TheHoleFillAddsOneLayer) {
  const TwoTurns f;
  std::vector<std::uint8_t> selected(64, 0);
  EXPECT_EQ(fill_holes({f.meshes, f.dates, &f.change, 0.1, {}}, selected).added, 32u);
  for (std::uint32_t t = 0; t < 32; ++t) EXPECT_EQ(selected[t] + selected[32 + t], 1) << t;
}

TEST(OneLayerPerPass, ATriangleReachingPastTheOthersEdgeStaysOneItCoversGoes) {
  // One pass, three triangles 1 cm apart in height, no shared corner: g; a larger one whose
  // centroid lies beyond g's long edge but which covers g's centroid (dropping it would leave
  // most of it uncovered); a small one lying on g.
  Mesh m;
  m.positions = {{0, 0, 0},           {1, 0, 0},           {0, 1, 0},             // g
                 {0.2f, 0, 0.01f},    {2.2f, 0, 0.01f},    {0.2f, 2, 0.01f},      // larger, reaching past g
                 {0.1f, 0.1f, 0.01f}, {0.5f, 0.1f, 0.01f}, {0.1f, 0.5f, 0.01f}};  // small, on g
  m.triangles = {{0, 1, 2}, {3, 4, 5}, {6, 7, 8}};
  m.triangle_ids.resize(3);
  const std::vector<Mesh> meshes{m};
  const std::vector<TimePoint> dates{TimePoint(std::chrono::days(1))};
  ChangeResult change;
  change.index.offsets = {0, 3};
  change.kept.assign(3, 1);
  change.layer_pairs = {{0, 1}, {0, 2}, {1, 2}};
  std::vector<std::uint8_t> selected{1, 1, 1};
  EXPECT_EQ(keep_one_layer({meshes, dates, &change, 0.1, {}}, 0, selected), 1u);
  EXPECT_EQ(selected, (std::vector<std::uint8_t>{1, 1, 0}));
  // 10 cm above g instead of 1 cm: beyond the distance threshold, nothing lies on g.
  for (std::size_t v = 6; v < 9; ++v) m.positions[v].z = 0.15f;
  const std::vector<Mesh> apart{m};
  selected = {1, 1, 1};
  change.layer_pairs = {{0, 1}, {0, 2}};
  EXPECT_EQ(keep_one_layer({apart, dates, &change, 0.1, {}}, 0, selected), 0u);
}

TEST(OneLayerPerPass, WithoutLayerPairsBothTurnsStay) {
  // The same mesh with no layer pairs listed (as before they were found): both sheets are
  // kept, which is what the pairs are there to prevent.
  TwoTurns f;
  f.change.layer_pairs = {};
  MosaicParams params;
  params.fill_holes = false;
  const MosaicSelection s = select_mosaic({f.meshes, f.dates, &f.change, 0.1, {}}, params);
  EXPECT_EQ(std::count(s.selected.begin(), s.selected.end(), 1), 64);
}

}  // namespace
}  // namespace citymesh
