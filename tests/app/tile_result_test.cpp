// SPDX-License-Identifier: MIT
// Tile result files: labels, pairs and the change step's figures of any values round-trip; damage under a valid
// checksum makes the tile "processed again", never a crash or a wrong result.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstring>
#include <fstream>
#include <map>
#include <random>

#include "citymesh/core/checksum.h"
#include "citymesh/core/read_file.h"
#include "test_support.h"
#include "tile_job.h"

namespace citymesh::app {
namespace {

constexpr std::uint64_t kFingerprint = 0x1234;
constexpr ResultDigests kDigests{kFingerprint, 0x5678};

/// A store of two acquisitions on 50 m tiles (what read_tile_result checks against).
TileStore two_acquisitions() {
  TileStore store;
  store.grid = {.tile_size = 50, .halo = 2, .origin = {651000, 6860000}};
  store.triangles = {1000, 1000};
  return store;
}

/// A result with labels and pairs sorted as process_tile writes them. `scan_order`: labels of
/// consecutive triangles over few dates; otherwise any value over its whole range.
TileResult random_result(std::uint32_t seed, bool scan_order) {
  std::mt19937_64 rng(seed);
  TileResult r;
  r.key = {13020, -7};
  r.triangles_in_tile = 4321;
  r.seconds_detect = 0.25;
  r.change.consistent_pairs = rng();
  r.change.conflict_candidates = rng();
  r.change.exact_tests = rng();
  r.change.marked_voxels = 77;
  r.change.seconds_grids = 0.125;
  r.change.seconds_time_series = 1e-3;
  for (std::uint32_t k = 0; k < 700; ++k) {
    OwnedLabel l{.acquisition = scan_order ? k / 400 : static_cast<std::uint32_t>(rng()),
                 .index = scan_order ? 10 + k : static_cast<std::uint32_t>(rng()),
                 .state = static_cast<TriangleState>(rng() % 3),
                 .kept = static_cast<std::uint8_t>(rng() % 2),
                 .sustainable = static_cast<std::uint8_t>(rng() % 2),
                 .refutes = static_cast<std::uint8_t>(rng() % 2),
                 .selected = static_cast<std::uint8_t>(rng() % 2),
                 .notes = static_cast<std::uint8_t>(rng())};
    l.first_ms = scan_order ? 1767607200000 + std::int64_t(k / 100) * 86400000 : static_cast<std::int64_t>(rng());
    l.last_ms = scan_order ? l.first_ms + 2592000000 : static_cast<std::int64_t>(rng());
    r.labels.push_back(l);
  }
  std::sort(r.labels.begin(), r.labels.end(), by_triangle);
  for (std::uint32_t k = 0; k < 900; ++k) {
    // Any values, the extremes among them: each field a delta against the pair before.
    const auto any = [&] { return k % 7 == 3 ? UINT32_MAX : static_cast<std::uint32_t>(rng()); };
    r.pairs.push_back({any(), any(), k % 5 == 1 ? 0 : any(), any()});
  }
  for (std::uint32_t k = 0; k < 300; ++k) {
    r.refuted.push_back({scan_order ? k / 200 : static_cast<std::uint32_t>(rng()),
                         scan_order ? 3 * k : static_cast<std::uint32_t>(rng())});
  }
  std::sort(r.refuted.begin(), r.refuted.end());
  r.selected.resize(2);
  r.passes = {0, 1};
  for (TilePiece& p : r.selected) p.mesh.origin = {651000 + 50 * 13020.0, 6860000 - 50 * 7.0, 0};
  return r;
}

void expect_same_labels(const std::vector<OwnedLabel>& a, const std::vector<OwnedLabel>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t k = 0; k < a.size(); ++k) {
    EXPECT_EQ(std::memcmp(&a[k], &b[k], sizeof(OwnedLabel)), 0) << "label " << k;
  }
}

TEST(TileResult, LabelsAndPairsOfAnyValueRoundTrip) {
  test::TempDir tmp;
  const TileStore store = two_acquisitions();
  for (const bool scan_order : {false, true}) {
    const TileResult r = random_result(scan_order ? 1 : 2, scan_order);
    write_tile_result(tmp / "t.bin", r, kDigests);
    const std::optional<TileResult> back = read_tile_result(tmp / "t.bin", kFingerprint, store);
    ASSERT_TRUE(back.has_value());
    EXPECT_EQ(back->key, r.key);
    EXPECT_EQ(back->triangles_in_tile, r.triangles_in_tile);
    EXPECT_EQ(back->seconds_detect, r.seconds_detect);
    EXPECT_EQ(back->change.consistent_pairs, r.change.consistent_pairs);
    EXPECT_EQ(back->change.conflict_candidates, r.change.conflict_candidates);
    EXPECT_EQ(back->change.exact_tests, r.change.exact_tests);
    EXPECT_EQ(back->change.marked_voxels, r.change.marked_voxels);
    EXPECT_EQ(back->change.seconds_grids, r.change.seconds_grids);
    EXPECT_EQ(back->change.seconds_time_series, r.change.seconds_time_series);
    expect_same_labels(back->labels, r.labels);
    EXPECT_EQ(back->pairs.size(), r.pairs.size());
    EXPECT_EQ(back->pairs.decoded(), r.pairs.decoded());
    EXPECT_EQ(back->refuted, r.refuted);
    // Without the pairs, as the assembly reads it when no labelled PLY is written.
    const std::optional<TileResult> no_pairs = read_tile_result(tmp / "t.bin", kFingerprint, store, {.pairs = false});
    ASSERT_TRUE(no_pairs.has_value());
    expect_same_labels(no_pairs->labels, r.labels);
    EXPECT_TRUE(no_pairs->pairs.empty());
    EXPECT_EQ(no_pairs->selected.size(), r.selected.size());
    // The labels alone, as a later-phase neighbour reads them.
    const std::optional<std::vector<OwnedLabel>> labels = read_tile_labels(tmp / "t.bin", kFingerprint, store);
    ASSERT_TRUE(labels.has_value());
    expect_same_labels(*labels, r.labels);
    // Another config's result is not this run's.
    EXPECT_FALSE(read_tile_result(tmp / "t.bin", kFingerprint + 1, store).has_value());
    EXPECT_FALSE(read_tile_labels(tmp / "t.bin", kFingerprint + 1, store).has_value());
    // Resuming asks only whether it is whole and this run's.
    EXPECT_TRUE(tile_result_is_finished(tmp / "t.bin", kFingerprint, store));
    EXPECT_FALSE(tile_result_is_finished(tmp / "t.bin", kFingerprint + 1, store));
    EXPECT_FALSE(tile_result_is_finished(tmp / "none.bin", kFingerprint, store));
  }
}

TEST(TileResult, ATornOrDamagedResultIsNotFinished) {
  test::TempDir tmp;
  const TileStore store = two_acquisitions();
  write_tile_result(tmp / "t.bin", random_result(6, true), kDigests);
  const std::string good = *read_file_bytes(tmp / "t.bin");
  std::mt19937 rng(7);
  for (int trial = 0; trial < 50; ++trial) {
    std::string bytes = good;
    if (trial % 2 == 0) {
      bytes.resize(rng() % bytes.size());  // a write cut short
    } else {
      bytes[rng() % bytes.size()] ^= static_cast<char>(1 + rng() % 255);  // any byte, the checksum's too
    }
    std::ofstream(tmp / "bad.bin", std::ios::binary) << bytes;
    EXPECT_FALSE(tile_result_is_finished(tmp / "bad.bin", kFingerprint, store)) << "trial " << trial;
  }
}

TEST(TileResult, AResultMadeBeforeAnAcquisitionWasAddedReadsWithAnEmptyPieceForIt) {
  test::TempDir tmp;
  const TileResult r = random_result(4, true);  // two acquisitions' pieces
  write_tile_result(tmp / "t.bin", r, kDigests);
  TileStore three = two_acquisitions();
  three.triangles.push_back(500);
  const std::optional<TileResult> back = read_tile_result(tmp / "t.bin", kFingerprint, three);
  ASSERT_TRUE(back.has_value());
  ASSERT_EQ(back->selected.size(), 3u);
  EXPECT_EQ(back->selected[2].triangle_count(), 0u);
  EXPECT_EQ(back->selected[2].mesh.origin, back->selected[0].mesh.origin);
  expect_same_labels(back->labels, r.labels);
  // (A result holding more acquisitions than the store: the test below.)
}

/// A piece of one triangle of acquisition `a`, in the tile's frame.
TilePiece one_triangle(std::uint32_t a) {
  TilePiece p;
  p.mesh.origin = {651000 + 50 * 13020.0, 6860000 - 50 * 7.0, 0};
  for (const Vec3f v : {Vec3f{1, 1, 0}, Vec3f{2, 1, 0}, Vec3f{1, 2, 0}}) {
    p.mesh.positions.push_back(v);
    p.mesh.sensor_positions.push_back({0, 0, 2});
  }
  p.vertex_ids = {7, 8, 9};
  p.mesh.triangles.push_back({0, 1, 2});
  p.mesh.triangle_ids.push_back({a, 0, 12});
  p.triangle_index.push_back(12);
  p.roles.push_back(TileRole::owned);
  return p;
}

TEST(TileResult, AResultMadeBeforeTheLastAcquisitionWasWithdrawnReadsWhenItHoldsNoneOfIt) {
  // Three acquisitions when it was written; the store now lists two (the third withdrawn).
  test::TempDir tmp;
  TileResult r = random_result(4, true);  // labels of acquisitions 0 and 1
  r.selected = {one_triangle(0), one_triangle(1), TilePiece{}};
  r.selected[2].mesh.origin = r.selected[0].mesh.origin;
  write_tile_result(tmp / "t.bin", r, kDigests);
  const TileStore two = two_acquisitions();
  const std::optional<TileResult> back = read_tile_result(tmp / "t.bin", kFingerprint, two);
  ASSERT_TRUE(back.has_value());
  ASSERT_EQ(back->selected.size(), 2u);
  EXPECT_EQ(back->selected[1].triangle_count(), 1u);
  expect_same_labels(back->labels, r.labels);
  EXPECT_TRUE(read_tile_labels(tmp / "t.bin", kFingerprint, two).has_value());
  EXPECT_TRUE(tile_result_is_finished(tmp / "t.bin", kFingerprint, two));
  // One that holds a triangle of the withdrawn acquisition is not used (the digest, which
  // counts the tile's triangles of each acquisition, says so first).
  r.selected[2] = one_triangle(2);
  r.passes = {0, 1, 2};
  write_tile_result(tmp / "piece.bin", r, kDigests);
  EXPECT_FALSE(read_tile_result(tmp / "piece.bin", kFingerprint, two).has_value());
  EXPECT_FALSE(read_tile_labels(tmp / "piece.bin", kFingerprint, two).has_value());
  EXPECT_FALSE(tile_result_is_finished(tmp / "piece.bin", kFingerprint, two));
}

TEST(TileResult, ScanOrderedLabelsTakeUnderAQuarterOfTheFixedLayout) {
  test::TempDir tmp;
  TileResult r = random_result(3, true);
  r.pairs = {};
  write_tile_result(tmp / "t.bin", r, kDigests);
  // Version 04 took 32 bytes per label after an 80-byte header.
  EXPECT_LT(std::filesystem::file_size(tmp / "t.bin"), (80 + 32 * r.labels.size()) / 4);
}

TEST(TileResult, DamageUnderAValidChecksumIsProcessedAgainNeverACrash) {
  test::TempDir tmp;
  const TileStore store = two_acquisitions();
  const TileResult r = random_result(4, true);
  write_tile_result(tmp / "good.bin", r, kDigests);
  const std::string good = *read_file_bytes(tmp / "good.bin");
  std::mt19937 rng(5);
  int refused = 0;
  for (int trial = 0; trial < 500; ++trial) {
    std::string bytes = good;
    // A count or section size in the header (bytes 24-56, 80-96 and 184-200), or the varint
    // sections (after the 224-byte header).
    const std::size_t at = trial % 5 == 0   ? 24 + rng() % 32
                           : trial % 5 == 1 ? 80 + rng() % 16
                           : trial % 5 == 2 ? 184 + rng() % 16
                                            : 224 + rng() % 3000;
    bytes[at] = static_cast<char>(rng());
    const std::uint64_t sum = bulk_checksum(bytes.data(), bytes.size() - 8);
    std::memcpy(bytes.data() + bytes.size() - 8, &sum, 8);
    std::ofstream(tmp / "bad.bin", std::ios::binary) << bytes;
    const std::optional<TileResult> back = read_tile_result(tmp / "bad.bin", kFingerprint, store);
    if (!back) ++refused;
    // The labels alone are refused whenever damage reaches the header or the labels.
    const std::optional<std::vector<OwnedLabel>> labels = read_tile_labels(tmp / "bad.bin", kFingerprint, store);
    if (labels && back) expect_same_labels(*labels, back->labels);
  }
  EXPECT_GT(refused, 250);
}

TEST(TileResult, KeepsWhatItWasMadeFromAndIsWrittenAgainUnderANewDigestUnchanged) {
  test::TempDir tmp;
  const TileStore store = two_acquisitions();
  TileResult r = random_result(8, true);
  r.settled_fingerprint = 0x9abc;
  write_tile_result(tmp / "t.bin", r, kDigests);
  const std::optional<ResultOrigin> origin = tile_result_origin(tmp / "t.bin");
  ASSERT_TRUE(origin.has_value());
  EXPECT_EQ(origin->inputs, kDigests.inputs);
  EXPECT_EQ(origin->settled, r.settled_fingerprint);
  EXPECT_FALSE(origin->kept);
  // Not when the file holds a result made from something else than the caller saw.
  ResultOrigin other = *origin;
  ++other.settled;
  EXPECT_FALSE(restamp_tile_result(tmp / "t.bin", store, other, kFingerprint + 7, r.passes));
  EXPECT_TRUE(tile_result_is_finished(tmp / "t.bin", kFingerprint, store)) << "left as it was";
  ASSERT_TRUE(restamp_tile_result(tmp / "t.bin", store, *origin, kFingerprint + 7, r.passes));
  EXPECT_TRUE(tile_result_is_finished(tmp / "t.bin", kFingerprint + 7, store));
  EXPECT_FALSE(tile_result_is_finished(tmp / "t.bin", kFingerprint, store));
  const std::optional<TileResult> back = read_tile_result(tmp / "t.bin", kFingerprint + 7, store);
  ASSERT_TRUE(back.has_value());
  expect_same_labels(back->labels, r.labels);
  EXPECT_EQ(back->refuted, r.refuted);
  EXPECT_EQ(back->settled_fingerprint, r.settled_fingerprint);
  const std::optional<ResultOrigin> again = tile_result_origin(tmp / "t.bin");
  ASSERT_TRUE(again.has_value());
  EXPECT_EQ(again->inputs, kDigests.inputs);
  EXPECT_TRUE(again->kept) << "the report tells kept results from processed ones by it";
  // Nothing to write again: no file, or a damaged one (left as it is).
  EXPECT_FALSE(restamp_tile_result(tmp / "none.bin", store, *origin, 1, r.passes));
  EXPECT_FALSE(tile_result_origin(tmp / "none.bin").has_value());
  std::string bytes = *read_file_bytes(tmp / "t.bin");
  bytes[300] ^= 1;
  std::ofstream(tmp / "bad.bin", std::ios::binary) << bytes;
  EXPECT_TRUE(tile_result_origin(tmp / "bad.bin").has_value()) << "the header alone is read";
  EXPECT_FALSE(restamp_tile_result(tmp / "bad.bin", store, *origin, 1, r.passes)) << "but the whole file is checked";
  EXPECT_EQ(*read_file_bytes(tmp / "bad.bin"), bytes);
  // What a plan asks (run --plan): the origin of a whole result only, whatever its digest.
  const std::optional<ResultOrigin> whole = whole_tile_result_origin(tmp / "t.bin");
  ASSERT_TRUE(whole.has_value());
  EXPECT_EQ(whole->result, kFingerprint + 7);
  EXPECT_EQ(whole->inputs, kDigests.inputs);
  EXPECT_FALSE(whole_tile_result_origin(tmp / "bad.bin").has_value()) << "a bit flipped past the header";
  std::ofstream(tmp / "short.bin", std::ios::binary) << bytes.substr(0, 1000);
  EXPECT_TRUE(tile_result_origin(tmp / "short.bin").has_value());
  EXPECT_FALSE(whole_tile_result_origin(tmp / "short.bin").has_value()) << "cut short";
  EXPECT_FALSE(whole_tile_result_origin(tmp / "none.bin").has_value());
}

TEST(TileResult, AResultOfAnOlderVersionIsProcessedAgain) {
  test::TempDir tmp;
  const TileStore store = two_acquisitions();
  write_tile_result(tmp / "t.bin", random_result(9, true), kDigests);
  ASSERT_TRUE(tile_result_is_finished(tmp / "t.bin", kFingerprint, store));
  std::string bytes = *read_file_bytes(tmp / "t.bin");
  bytes[7] = '8';  // version 08: no list of the tile's acquisitions
  const std::uint64_t sum = bulk_checksum(bytes.data(), bytes.size() - 8);
  std::memcpy(bytes.data() + bytes.size() - 8, &sum, 8);
  std::ofstream(tmp / "v8.bin", std::ios::binary) << bytes;
  EXPECT_FALSE(tile_result_is_finished(tmp / "v8.bin", kFingerprint, store));
  EXPECT_FALSE(read_tile_result(tmp / "v8.bin", kFingerprint, store).has_value());
  EXPECT_FALSE(tile_result_origin(tmp / "v8.bin").has_value());
}

/// A result of a tile holding acquisitions `passes` (two of them) of `acquisitions`: labels,
/// pairs and refuted copies of both, sorted as process_tile writes them, and a selected
/// triangle of each.
TileResult result_of_two_passes(std::array<std::uint32_t, 2> passes, std::uint32_t acquisitions) {
  TileResult r = random_result(12, true);  // labels and refuted copies of acquisitions 0 and 1
  for (OwnedLabel& l : r.labels) l.acquisition = passes[l.acquisition];
  for (RefutedCopy& c : r.refuted) c.acquisition = passes[c.acquisition];
  r.pairs = {};
  for (std::uint32_t k = 0; k < 60; ++k) {  // sorted, the smaller end first
    r.pairs.push_back({passes[k / 40], k, passes[1], 1000 - k});
  }
  r.selected.assign(acquisitions, TilePiece{});
  for (TilePiece& p : r.selected) p.mesh.origin = one_triangle(0).mesh.origin;
  for (const std::uint32_t a : passes) r.selected[a] = one_triangle(a);
  r.passes = {passes.begin(), passes.end()};
  return r;
}

TEST(TileResult, AResultWhosePassesWereRenumberedIsWrittenAgainAsProcessingUnderTheNewNumberingWrites) {
  // Made when the tile held acquisitions 0 and 2 of three; a pass delivered late, older than
  // both, and another between them make them 1 and 3 of five.
  test::TempDir tmp;
  TileStore five = two_acquisitions();
  five.triangles = {1000, 1000, 1000, 1000, 1000};
  const TileResult made = result_of_two_passes({0, 2}, 3);
  write_tile_result(tmp / "t.bin", made, kDigests);
  const std::optional<ResultOrigin> origin = tile_result_origin(tmp / "t.bin");
  ASSERT_TRUE(origin.has_value());
  const std::vector<std::uint32_t> now{1, 3};
  ASSERT_TRUE(restamp_tile_result(tmp / "t.bin", five, *origin, kFingerprint + 1, now));
  EXPECT_TRUE(tile_result_origin(tmp / "t.bin")->kept);
  const std::optional<TileResult> back = read_tile_result(tmp / "t.bin", kFingerprint + 1, five);
  ASSERT_TRUE(back.has_value());
  EXPECT_EQ(back->passes, now);
  ASSERT_EQ(back->selected.size(), 5u);
  for (std::uint32_t a = 0; a < 5; ++a) {
    EXPECT_EQ(back->selected[a].triangle_count(), a == 1 || a == 3 ? 1u : 0u) << a;
    if (a == 1 || a == 3) {
      EXPECT_EQ(back->selected[a].mesh.triangle_ids[0].acquisition, a);
    }
  }
  // The file is, to the byte, that of the same tile processed under the new numbering (and
  // kept under the same digest).
  write_tile_result(tmp / "fresh.bin", result_of_two_passes({1, 3}, 5), kDigests);
  ASSERT_TRUE(restamp_tile_result(tmp / "fresh.bin", five, *origin, kFingerprint + 1, now));
  EXPECT_EQ(*read_file_bytes(tmp / "t.bin"), *read_file_bytes(tmp / "fresh.bin"));
  // And back when those two passes are removed again: the numbering it was made under (its
  // pieces past the three acquisitions listed now move down).
  TileStore three = five;
  three.triangles.resize(3);
  ASSERT_TRUE(restamp_tile_result(tmp / "t.bin", three, *origin, kFingerprint + 2, made.passes));
  write_tile_result(tmp / "first.bin", made, kDigests);
  ASSERT_TRUE(restamp_tile_result(tmp / "first.bin", three, *origin, kFingerprint + 2, made.passes));
  EXPECT_EQ(*read_file_bytes(tmp / "t.bin"), *read_file_bytes(tmp / "first.bin"));
  EXPECT_TRUE(tile_result_is_finished(tmp / "t.bin", kFingerprint + 2, three));

  // Not when the tile holds another number of passes, nor when the result names an
  // acquisition it did not list: left as it is (the tile is processed again).
  write_tile_result(tmp / "t.bin", made, kDigests);
  const std::string bytes = *read_file_bytes(tmp / "t.bin");
  EXPECT_FALSE(restamp_tile_result(tmp / "t.bin", five, *origin, kFingerprint + 1, std::vector<std::uint32_t>{1}));
  TileResult stray = made;
  stray.labels.back().acquisition = 3;  // past the last of its passes, still sorted
  write_tile_result(tmp / "stray.bin", stray, kDigests);
  const std::string stray_bytes = *read_file_bytes(tmp / "stray.bin");
  EXPECT_FALSE(restamp_tile_result(tmp / "stray.bin", five, *origin, kFingerprint + 1, now));
  EXPECT_EQ(*read_file_bytes(tmp / "stray.bin"), stray_bytes);
  EXPECT_EQ(*read_file_bytes(tmp / "t.bin"), bytes);
  // A piece of an acquisition it does not list: not a result of this tile.
  TileResult unlisted = made;
  unlisted.selected[1] = one_triangle(1);
  write_tile_result(tmp / "unlisted.bin", unlisted, kDigests);
  EXPECT_FALSE(tile_result_is_finished(tmp / "unlisted.bin", kFingerprint, five));
}

TEST(SettledSelection, AnswersAsAMapOfEveryNeighboursLabels) {
  // Up to eight neighbours own disjoint triangles of three acquisitions; each gives its labels
  // sorted, as its result holds them.
  std::mt19937 rng(6);
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<std::uint32_t> indices(3000);
    for (std::uint32_t k = 0; k < indices.size(); ++k) indices[k] = k * 7 + static_cast<std::uint32_t>(rng() % 7);
    std::shuffle(indices.begin(), indices.end(), rng);
    std::map<std::pair<std::uint32_t, std::uint32_t>, bool> expected;
    SettledSelection settled;
    const std::size_t neighbours = 1 + rng() % 8;
    for (std::size_t n = 0; n < neighbours; ++n) {
      std::vector<OwnedLabel> labels;
      for (std::size_t k = n; k < indices.size(); k += neighbours) {
        const OwnedLabel l{.acquisition = static_cast<std::uint32_t>(rng() % 3),
                           .index = indices[k],
                           .selected = static_cast<std::uint8_t>(rng() % 2)};
        if (expected.try_emplace({l.acquisition, l.index}, l.selected != 0).second) labels.push_back(l);
      }
      std::sort(labels.begin(), labels.end(), by_triangle);
      settled.add(labels);
    }
    ASSERT_EQ(settled.size(), expected.size());
    for (std::uint32_t a = 0; a < 3; ++a) {
      for (std::uint32_t index = 0; index < 3000 * 7; ++index) {
        const auto it = expected.find({a, index});
        const std::optional<bool> got = settled.selected(a, index);
        ASSERT_EQ(got.has_value(), it != expected.end()) << a << " " << index;
        if (got) {
          ASSERT_EQ(*got, it->second) << a << " " << index;
        }
      }
    }
  }
}

}  // namespace
}  // namespace citymesh::app
