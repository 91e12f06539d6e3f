// SPDX-License-Identifier: MIT
// Keyed pieces: subsets keep only the vertices their triangles use; merging names each key's
// vertex once, whatever piece it came from.
#include <gtest/gtest.h>

#include <stdexcept>

#include "citymesh/core/error.h"
#include "citymesh/core/keyed_piece.h"

namespace citymesh {
namespace {

/// A fan of triangles around vertex key `centre`, on the keys `ring` (ascending, above
/// `centre`); positions (key, 0, 0), source `acq`, source triangle = its index.
KeyedPiece fan(std::uint64_t centre, std::vector<std::uint64_t> ring, std::int32_t acq) {
  KeyedPiece p;
  p.keys.push_back(centre);
  p.keys.insert(p.keys.end(), ring.begin(), ring.end());
  for (const std::uint64_t k : p.keys) {
    p.positions.push_back({double(k), 0, 0});
    p.sensors.push_back({double(k), 0, 10});
  }
  for (std::uint32_t i = 1; i + 1 < p.keys.size(); ++i) {
    p.triangles.push_back({0, i, i + 1});
    p.ids.push_back({.acquisition = std::uint32_t(acq), .face = i});
    p.source_acq.push_back(acq);
    p.source_triangle.push_back(static_cast<std::int32_t>(i));
  }
  return p;
}

/// The triangles of `p` as key triples with their source triangle.
std::vector<std::array<std::uint64_t, 4>> keyed_triangles(const KeyedPiece& p) {
  std::vector<std::array<std::uint64_t, 4>> out;
  for (std::size_t t = 0; t < p.triangle_count(); ++t) {
    const Triangle& tri = p.triangles[t];
    out.push_back({p.keys[tri[0]], p.keys[tri[1]], p.keys[tri[2]], std::uint64_t(p.source_triangle[t])});
  }
  return out;
}

TEST(KeyedPiece, SubsetKeepsTheTrianglesInOrderOnTheVerticesTheyUse) {
  const KeyedPiece p = fan(1, {4, 9, 16, 25, 36}, 2);  // triangles (1,4,9) (1,9,16) (1,16,25) (1,25,36)
  const std::vector<std::uint32_t> chosen{3, 0};
  const KeyedPiece s = subset(p, chosen);
  s.check("subset");
  EXPECT_EQ(s.keys, (std::vector<std::uint64_t>{1, 4, 9, 25, 36}));
  EXPECT_EQ(keyed_triangles(s), (std::vector<std::array<std::uint64_t, 4>>{{1, 25, 36, 4}, {1, 4, 9, 1}}));
  EXPECT_EQ(s.sensors[3].x, 25.0);
  EXPECT_EQ(s.box().min.x, 1.0);
  EXPECT_EQ(s.box().max.x, 36.0);
}

TEST(KeyedPiece, MergingNamesEachKeyOnceAndKeepsEveryTriangle) {
  const KeyedPiece a = fan(1, {4, 9, 16}, 0), b = fan(4, {9, 30, 31}, 1);
  const std::vector<const KeyedPiece*> both{&a, &b};
  const KeyedPiece m = merge_pieces(both);
  m.check("merged");
  EXPECT_EQ(m.keys, (std::vector<std::uint64_t>{1, 4, 9, 16, 30, 31}));
  std::vector<std::array<std::uint64_t, 4>> expected = keyed_triangles(a);
  for (const auto& t : keyed_triangles(b)) expected.push_back(t);
  EXPECT_EQ(keyed_triangles(m), expected);
  EXPECT_EQ(m.source_acq, (std::vector<std::int32_t>{0, 0, 1, 1}));
}

TEST(KeyedPiece, MergingPiecesWithDifferentAttributesIsRefused) {
  const KeyedPiece a = fan(1, {4, 9}, 0);
  KeyedPiece b = fan(2, {5, 7}, 1);
  b.sensors.clear();
  const std::vector<const KeyedPiece*> both{&a, &b};
  EXPECT_THROW((void)merge_pieces(both), ProcessingError);
}

TEST(KeyedPiece, CheckRefusesKeysOutOfOrderAndCornersOutOfRange) {
  KeyedPiece p = fan(1, {4, 9}, 0);
  EXPECT_NO_THROW(p.check("fan"));
  KeyedPiece unordered = p;
  std::swap(unordered.keys[1], unordered.keys[2]);
  EXPECT_THROW(unordered.check("fan"), ProcessingError);
  p.triangles[0][2] = 3;
  EXPECT_THROW(p.check("fan"), ProcessingError);
}

}  // namespace
}  // namespace citymesh
