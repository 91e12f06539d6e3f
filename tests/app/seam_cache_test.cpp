// SPDX-License-Identifier: MIT
// A stitched part's outcome, as the seam cache and the cluster's ranks hand it back.
#include "seam_cache.h"

#include <gtest/gtest.h>

#include "citymesh/core/error.h"

namespace citymesh::app {
namespace {

TEST(SeamPartOutcome, EveryCountComesBackInItsPlace) {
  PartOutcome o;
  StitchStats& s = o.stats;
  // Distinct values: a count read into another's place shows.
  s.vertices_snapped = 1, s.edges_split = 2, s.triangles_uncovered = 3, s.triangles_clipped = 4;
  s.strips = 5, s.triangles_added = 6, s.vertices_welded = 7, s.gaps_filled = 8, s.rejected = 9;
  s.triangles_split = 10;
  o.box = {{-1.5, 2.25, 3}, {4, 5.125, 6}};
  o.cut_triangles = 11;
  o.digest = 0x0123456789abcdefull;
  o.reused = true;
  o.key_parts = {{0, -3, 4}, {2, 5, -6}};
  const PartOutcome back = outcome_from(nlohmann::json::parse(outcome_json(o).dump()));
  const StitchStats& b = back.stats;
  EXPECT_EQ(b.vertices_snapped, 1u);
  EXPECT_EQ(b.edges_split, 2u);
  EXPECT_EQ(b.triangles_uncovered, 3u);
  EXPECT_EQ(b.triangles_clipped, 4u);
  EXPECT_EQ(b.strips, 5u);
  EXPECT_EQ(b.triangles_added, 6u);
  EXPECT_EQ(b.vertices_welded, 7u);
  EXPECT_EQ(b.gaps_filled, 8u);
  EXPECT_EQ(b.rejected, 9u);
  EXPECT_EQ(b.triangles_split, 10u);
  EXPECT_EQ(back.box.min, o.box.min);
  EXPECT_EQ(back.box.max, o.box.max);
  EXPECT_EQ(back.cut_triangles, 11u);
  EXPECT_EQ(back.digest, o.digest);
  EXPECT_TRUE(back.reused);
  EXPECT_EQ(back.key_parts, o.key_parts);
}

TEST(SeamPartOutcome, AnOutcomeWithCountsMissingIsRefused) {
  nlohmann::json j = outcome_json(PartOutcome{});
  j["counts"].erase(9);  // as the previous format wrote: nine counts
  EXPECT_THROW(outcome_from(j), ProcessingError);
}

}  // namespace
}  // namespace citymesh::app
