// SPDX-License-Identifier: MIT
// The tiled run's labels: the consistent pairs spilled to disk come back sorted and unique,
// and the assembly's compact labels expand to exactly what the tiles handed in.
#include "tile_assembly.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <set>
#include <span>

#include "citymesh/core/error.h"
#include "citymesh/core/record_file.h"
#include "detect_output.h"
#include "pair_spill.h"
#include "test_support.h"

namespace citymesh::app {
namespace {

std::vector<std::uint32_t> flat(const std::set<TrianglePair>& pairs) {
  std::vector<std::uint32_t> v;
  for (const auto& [a, b] : pairs) v.insert(v.end(), {a, b});
  return v;
}

TEST(PairSpill, WritesEveryPairOnceInOrderWhateverTheOrderAdded) {
  test::TempDir tmp;
  std::minstd_rand rng(7);
  std::set<TrianglePair> expected;
  {
    // A small range: pairs land in dozens of files, each appended to many times.
    PairSpill spill(tmp / "spill", 1000);
    for (int batch = 0; batch < 40; ++batch) {
      std::vector<TrianglePair> pairs;
      for (int k = 0; k < 500; ++k) {
        const auto a = static_cast<std::uint32_t>(rng() % 50000), b = a + 1 + static_cast<std::uint32_t>(rng() % 100);
        pairs.emplace_back(a, b);
        if (k % 7 == 0) pairs.emplace_back(a, b);  // repeats, as neighbouring tiles give
        expected.emplace(a, b);
      }
      // Half the batches in order, as tiles give them (no regrouping), half shuffled.
      if (batch % 2 == 0)
        std::sort(pairs.begin(), pairs.end());
      else
        std::shuffle(pairs.begin(), pairs.end(), rng);
      spill.add(pairs);
    }
    EXPECT_EQ(spill.write_sorted(tmp / "pairs.bin", kPairsMagic), expected.size());
    EXPECT_TRUE(std::filesystem::exists(tmp / "spill"));
  }
  EXPECT_FALSE(std::filesystem::exists(tmp / "spill")) << "the spill folder outlived the spill";
  EXPECT_EQ(read_u32_records(tmp / "pairs.bin", kPairsMagic, "pairs"), flat(expected));
  // The same file as written in one piece.
  write_u32_records(tmp / "whole.bin", kPairsMagic, flat(expected));
  EXPECT_EQ(test::read_text(tmp / "pairs.bin"), test::read_text(tmp / "whole.bin"));
}

TEST(PairSpill, NoPairsGiveAnEmptyListAndADamagedSpillAnError) {
  test::TempDir tmp;
  PairSpill empty(tmp / "empty");
  EXPECT_EQ(empty.write_sorted(tmp / "none.bin", kPairsMagic), 0u);
  EXPECT_TRUE(read_u32_records(tmp / "none.bin", kPairsMagic, "pairs").empty());

  PairSpill spill(tmp / "spill", 10);
  spill.add(std::vector<TrianglePair>{{3, 4}, {25, 30}});
  std::filesystem::resize_file(tmp / "spill/2.pairs", 5);  // torn: not whole pairs
  EXPECT_THROW((void)spill.write_sorted(tmp / "bad.bin", kPairsMagic), InputError);
  EXPECT_FALSE(std::filesystem::exists(tmp / "bad.bin"));
}

/// One tile's labels for triangles [begin, end) of each acquisition, random values over a few
/// dates, and random pairs among them.
TileResult tile_of(std::uint32_t begin, std::uint32_t end, std::minstd_rand& rng) {
  TileResult r;
  r.key = {static_cast<std::int32_t>(begin), 0};
  const std::int64_t dates[] = {1767607200000, 1770199200000, 1770544800000};
  for (std::uint32_t a = 0; a < 2; ++a) {
    for (std::uint32_t t = begin; t < end; ++t) {
      OwnedLabel l{.acquisition = a,
                   .index = t,
                   .state = static_cast<TriangleState>(rng() % 3),
                   .kept = static_cast<std::uint8_t>(rng() % 2),
                   .sustainable = static_cast<std::uint8_t>(rng() % 2),
                   .refutes = static_cast<std::uint8_t>(rng() % 2)};
      l.first_ms = dates[rng() % 3];
      l.last_ms = dates[rng() % 3];
      r.labels.push_back(l);
      r.pairs.push_back({0, t, 1, begin + static_cast<std::uint32_t>(rng() % (end - begin))});
    }
  }
  return r;
}

/// Two acquisitions of 300 triangles each, in three tiles.
constexpr std::uint32_t kTrianglesEach = 300;
TileStore store_of_two() {
  TileStore store;
  store.triangles = {kTrianglesEach, kTrianglesEach};
  return store;
}
std::vector<TileResult> three_tiles(std::minstd_rand& rng) {
  return {tile_of(0, 120, rng), tile_of(120, 250, rng), tile_of(250, kTrianglesEach, rng)};
}

TEST(TileAssembly, CompactLabelsExpandToWhatTheTilesGave) {
  test::TempDir tmp;
  const TileStore store = store_of_two();
  std::minstd_rand rng(11);
  const std::vector<TileResult> tiles = three_tiles(rng);
  std::set<TrianglePair> pairs;
  for (const TileResult& r : tiles) {
    for (const LabelPair& p : r.pairs)
      pairs.emplace(p.a_acquisition * 300 + p.a_index, p.b_acquisition * 300 + p.b_index);
  }
  TileAssembly assembly(store, tmp / "pairs");
  for (const std::size_t k : {2, 0, 1}) assembly.add(tiles[k]);  // any order
  for (std::uint32_t a = 0; a < 2; ++a) {
    const ChangeResult c = assembly.labels(a);
    ASSERT_EQ(c.state.size(), 300u);
    for (const TileResult& r : tiles) {
      for (const OwnedLabel& l : r.labels) {
        if (l.acquisition != a) continue;
        EXPECT_EQ(c.state[l.index], l.state);
        EXPECT_EQ(c.kept[l.index], l.kept);
        EXPECT_EQ(c.sustainable[l.index], l.sustainable);
        EXPECT_EQ(c.refutes[l.index], l.refutes);
        EXPECT_EQ(c.first_seen[l.index].time_since_epoch().count(), l.first_ms);
        EXPECT_EQ(c.last_seen[l.index].time_since_epoch().count(), l.last_ms);
      }
    }
  }
  EXPECT_EQ(assembly.write_pairs(tmp / "pairs.bin", kPairsMagic), pairs.size());
  EXPECT_EQ(read_u32_records(tmp / "pairs.bin", kPairsMagic, "pairs"), flat(pairs));
}

TEST(TileAssembly, CopiesATileFoundRefutingRaiseTheirOwnersRefutes) {
  test::TempDir tmp;
  const TileStore store = store_of_two();
  std::minstd_rand rng(17);
  std::vector<TileResult> tiles = three_tiles(rng);
  // Each tile refutes some triangles of the others (repeats across tiles allowed).
  std::set<std::pair<std::uint32_t, std::uint32_t>> raised;
  for (TileResult& r : tiles) {
    for (int k = 0; k < 40; ++k) {
      const RefutedCopy c{static_cast<std::uint32_t>(rng() % 2), static_cast<std::uint32_t>(rng() % kTrianglesEach)};
      r.refuted.push_back(c);
      raised.emplace(c.acquisition, c.index);
    }
    std::sort(r.refuted.begin(), r.refuted.end());
    r.refuted.erase(std::unique(r.refuted.begin(), r.refuted.end()), r.refuted.end());
  }
  TileAssembly assembly(store, tmp / "pairs");
  for (const TileResult& r : tiles) assembly.add(r);
  std::size_t raised_here = 0;
  for (std::uint32_t a = 0; a < 2; ++a) {
    const ChangeResult c = assembly.labels(a);
    const ChangeResult window = assembly.labels(a, 100, 200);
    for (const TileResult& r : tiles) {
      for (const OwnedLabel& l : r.labels) {
        if (l.acquisition != a) continue;
        const bool refutes = l.refutes != 0 || raised.contains({a, l.index});
        EXPECT_EQ(c.refutes[l.index], refutes ? 1 : 0) << a << " " << l.index;
        if (l.index >= 100 && l.index < 200) {
          EXPECT_EQ(window.refutes[l.index - 100], c.refutes[l.index]);
        }
        raised_here += l.refutes == 0 && refutes ? 1 : 0;
      }
    }
  }
  EXPECT_GT(raised_here, 20u);  // raised only by another tile
  // A copy outside the input is refused.
  TileResult bad = tile_of(0, 120, rng);
  bad.refuted = {{1, kTrianglesEach}};
  TileAssembly other(store, tmp / "other");
  EXPECT_THROW(other.add(bad), ProcessingError);
}

TEST(TileAssembly, RefusesLabelsWhenATileIsMissing) {
  test::TempDir tmp;
  TileStore store;
  store.triangles = {300, 300};
  std::minstd_rand rng(3);
  TileAssembly assembly(store, tmp / "pairs");
  assembly.add(tile_of(0, 120, rng));
  EXPECT_THROW((void)assembly.labels(0), ProcessingError);
  TileAssembly without(store, std::nullopt);
  EXPECT_THROW((void)without.labels(0), ProcessingError);
}

TEST(LabelSpill, LabelsAddedInPiecesComeBackByIndexAndGapsOrRepeatsAreRefused) {
  test::TempDir tmp;
  std::filesystem::create_directories(tmp / "spill");
  LabelSpill spill(tmp / "spill");
  std::vector<LabelSpill::Label> all;
  for (std::uint32_t t = 0; t < 1000; ++t) {
    all.push_back({t, static_cast<std::uint8_t>(t % 31), static_cast<std::uint16_t>(t % 7),
                   static_cast<std::uint16_t>(t % 65536)});
  }
  std::minstd_rand rng(5);
  std::vector<LabelSpill::Label> shuffled = all;
  std::shuffle(shuffled.begin(), shuffled.end(), rng);
  for (std::size_t first = 0; first < shuffled.size(); first += 97) {
    spill.add(2, std::span(shuffled).subspan(first, std::min<std::size_t>(97, shuffled.size() - first)));
  }
  const std::vector<LabelSpill::Label> back = spill.read(2, 1000);
  ASSERT_EQ(back.size(), all.size());
  for (std::size_t t = 0; t < all.size(); ++t) {
    EXPECT_EQ(back[t].index, all[t].index);
    EXPECT_EQ(back[t].flags, all[t].flags);
    EXPECT_EQ(back[t].first, all[t].first);
    EXPECT_EQ(back[t].last, all[t].last);
  }
  EXPECT_THROW((void)spill.read(2, 1001), ProcessingError);  // one triangle never labelled
  EXPECT_THROW((void)spill.read(3, 10), ProcessingError);    // no file: none labelled
  spill.add(4, std::span(all).subspan(0, 2));
  spill.add(4, std::span(all).subspan(1, 1));  // triangle 1 twice, and 2 missing
  EXPECT_THROW((void)spill.read(4, 3), ProcessingError);
}

TEST(LabelSpill, RefutedTrianglesComeBackSortedOnceByWindowAndDamageIsAnError) {
  test::TempDir tmp;
  std::filesystem::create_directories(tmp / "spill");
  LabelSpill spill(tmp / "spill");
  EXPECT_TRUE(spill.refuted(0, 100, 0, 100).empty());  // no tile found any
  spill.add_refuted(0, std::vector<std::uint32_t>{40, 7, 99});
  spill.add_refuted(0, std::vector<std::uint32_t>{7, 0});  // repeats from another tile
  spill.add_refuted(1, std::vector<std::uint32_t>{5});
  EXPECT_EQ(spill.refuted(0, 100, 0, 100), (std::vector<std::uint32_t>{0, 7, 40, 99}));
  EXPECT_EQ(spill.refuted(0, 100, 7, 99), (std::vector<std::uint32_t>{7, 40}));
  EXPECT_EQ(spill.refuted(1, 100, 0, 100), (std::vector<std::uint32_t>{5}));
  // A triangle the acquisition does not have, and a torn file, are errors naming them.
  EXPECT_THROW((void)spill.refuted(0, 99, 0, 99), ProcessingError);
  std::filesystem::resize_file(tmp / "spill/1.refuted", 3);
  EXPECT_THROW((void)spill.refuted(1, 100, 0, 100), InputError);
}

TEST(LabelSpill, WindowsOfTheLabelsAreSlicesOfTheWholeAndAGapInOneIsRefused) {
  test::TempDir tmp;
  std::filesystem::create_directories(tmp / "spill");
  LabelSpill spill(tmp / "spill");
  std::vector<LabelSpill::Label> all;
  for (std::uint32_t t = 0; t < 200000; ++t) {  // more than one read of the file
    all.push_back(
        {t, static_cast<std::uint8_t>(t % 29), static_cast<std::uint16_t>(t % 5), static_cast<std::uint16_t>(t % 9)});
  }
  std::vector<LabelSpill::Label> shuffled = all;
  std::shuffle(shuffled.begin(), shuffled.end(), std::minstd_rand(8));
  spill.add(1, shuffled);
  const std::vector<LabelSpill::Label> whole = spill.read(1, all.size());
  for (const auto& [begin, end] :
       {std::pair{0u, 1u}, std::pair{1u, 70001u}, std::pair{70001u, 200000u}, std::pair{5u, 5u}}) {
    const std::vector<LabelSpill::Label> window = spill.read(1, all.size(), begin, end);
    ASSERT_EQ(window.size(), end - begin);
    for (std::size_t i = 0; i < window.size(); ++i) {
      EXPECT_EQ(window[i].index, begin + i);
      EXPECT_EQ(window[i].flags, whole[begin + i].flags);
      EXPECT_EQ(window[i].last, whole[begin + i].last);
    }
  }
  EXPECT_THROW((void)spill.read(1, all.size(), 10, 200001), ProcessingError);  // past the end
  // Triangle 1 twice and 2 never: a window holding 2 but not the repeat still sees the gap.
  spill.add(4, std::span(all).subspan(0, 2));
  spill.add(4, std::span(all).subspan(1, 1));
  EXPECT_THROW((void)spill.read(4, 3, 2, 3), ProcessingError);
  EXPECT_EQ(spill.read(4, 3, 0, 1).size(), 1u);  // triangle 0 alone is labelled once
}

}  // namespace
}  // namespace citymesh::app
