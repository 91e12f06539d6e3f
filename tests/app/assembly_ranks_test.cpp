// SPDX-License-Identifier: MIT
// What an MPI rank that read and filed a tile result leaves for rank 0 comes back whole.
#include "assembly_ranks.h"

#include <gtest/gtest.h>

#include "citymesh/core/error.h"

namespace citymesh::app {
namespace {

TEST(FiledResult, EveryFieldComesBackInItsPlace) {
  FiledResult r;
  r.filed.parts = {{0, -3, 4}, {2, 5, -6}};
  r.filed.files = {"/shared/seams.a.1/0_-3_4.1_2.tile", "/shared/seams.a.1/2_5_-6.1_2.tile"};
  r.filed.boxes = {{{-1.5, 2.25, 3}, {4, 5.125, 6}}, Box3d{}};  // an empty box too: infinite bounds
  r.filed.source_sizes = {7, 0, 9};
  // Distinct values: a field read into another's place shows.
  TileTally& t = r.tally;
  t.owned = 1, t.candidates = 2, t.seen_through = 3, t.filled = 4, t.fill_left_out = 5;
  std::uint64_t count = 10;
  for (const auto field : kChangeCounts) t.change.*field = count++;
  double seconds = 0.1;
  for (const auto field : kChangeSeconds) t.change.*field = (seconds += 1.0 / 3.0);
  t.seconds_read = 1.0 / 7.0, t.seconds_detect = 2.0 / 7.0, t.seconds_mosaic = 3.0 / 7.0;

  const FiledResult back = filed_result_from(nlohmann::json::parse(filed_result_json(r).dump()));
  EXPECT_EQ(back.filed.parts, r.filed.parts);
  EXPECT_EQ(back.filed.files, r.filed.files);
  ASSERT_EQ(back.filed.boxes.size(), 2u);
  EXPECT_EQ(back.filed.boxes[0].min, r.filed.boxes[0].min);
  EXPECT_EQ(back.filed.boxes[0].max, r.filed.boxes[0].max);
  EXPECT_TRUE(back.filed.boxes[1].empty());
  EXPECT_EQ(back.filed.source_sizes, r.filed.source_sizes);
  const TileTally& b = back.tally;
  EXPECT_EQ(b.owned, 1u);
  EXPECT_EQ(b.candidates, 2u);
  EXPECT_EQ(b.seen_through, 3u);
  EXPECT_EQ(b.filled, 4u);
  EXPECT_EQ(b.fill_left_out, 5u);
  for (const auto field : kChangeCounts) EXPECT_EQ(b.change.*field, t.change.*field);
  // Seconds to the bit: the root's sums must be one process's.
  for (const auto field : kChangeSeconds) EXPECT_EQ(b.change.*field, t.change.*field);
  EXPECT_EQ(b.seconds_read, t.seconds_read);
  EXPECT_EQ(b.seconds_detect, t.seconds_detect);
  EXPECT_EQ(b.seconds_mosaic, t.seconds_mosaic);
}

TEST(FiledResult, AFilingWhoseListsDisagreeOrWhoseCountsAreShortIsRefused) {
  FiledResult r;
  r.filed.parts = {{0, 1, 2}};
  r.filed.files = {"a.tile"};
  r.filed.boxes = {Box3d{}};
  nlohmann::json j = filed_result_json(r);
  nlohmann::json more_files = j;
  more_files["files"].push_back("b.tile");
  EXPECT_THROW(filed_result_from(more_files), ProcessingError);
  nlohmann::json short_counts = j;
  short_counts["tally"]["counts"].erase(4);
  EXPECT_THROW(filed_result_from(short_counts), nlohmann::json::exception);
}

}  // namespace
}  // namespace citymesh::app
