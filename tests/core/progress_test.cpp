// SPDX-License-Identifier: MIT
#include "citymesh/core/progress.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace citymesh {
namespace {

/// The lines a StageProgress says, and the (done, total, ETA) each one reads.
struct Heard {
  struct Line {
    unsigned long long done = 0, total = 0;
    double eta = -1;
  };
  std::mutex mutex;
  std::vector<std::string> text;

  std::function<void(const std::string&)> sink() {
    return [this](const std::string& line) {
      const std::lock_guard lock(mutex);
      text.push_back(line);
    };
  }
  [[nodiscard]] Line read(std::size_t k) const {
    Line l;
    const std::string& s = text.at(k);
    const std::size_t at = s.find("stitched ");
    EXPECT_NE(at, std::string::npos) << s;
    EXPECT_EQ(std::sscanf(s.c_str() + at, "stitched %llu/%llu, ETA %lf s", &l.done, &l.total, &l.eta), 3) << s;
    return l;
  }
};

/// `threads` threads each advancing `progress` by one, `each` times.
void advance_from_threads(StageProgress& progress, int threads, int each) {
  std::vector<std::thread> pool;
  for (int t = 0; t < threads; ++t) {
    pool.emplace_back([&progress, each] {
      for (int i = 0; i < each; ++i) progress.advance();
    });
  }
  for (std::thread& t : pool) t.join();
}

TEST(StageProgress, AQuickStageSaysOneLineItsLastAndOnlyOnce) {
  Heard heard;
  StageProgress progress({.stage = "parts stitched", .total = 1000, .interval = 1e9, .say = heard.sink()});
  advance_from_threads(progress, 4, 250);
  progress.finish();    // already said: nothing more
  progress.advance(5);  // past the total: still nothing, and the count stays
  ASSERT_EQ(heard.text.size(), 1u);
  const Heard::Line last = heard.read(0);
  EXPECT_EQ(last.done, 1000u);
  EXPECT_EQ(last.total, 1000u);
  EXPECT_EQ(last.eta, 0.0);
  EXPECT_NE(heard.text[0].find(", memory "), std::string::npos) << heard.text[0];
  EXPECT_EQ(progress.done(), 1000u);
}

TEST(StageProgress, LinesComeInTheOrderOfTheCountAndEndAtTheTotal) {
  Heard heard;
  StageProgress progress({.stage = "parts stitched", .total = 400, .interval = 0, .say = heard.sink()});
  advance_from_threads(progress, 4, 100);
  ASSERT_EQ(heard.text.size(), 400u);  // no interval: every item says its line
  for (std::size_t k = 0; k < heard.text.size(); ++k) {
    const Heard::Line l = heard.read(k);
    EXPECT_EQ(l.done, k + 1);
    EXPECT_EQ(l.total, 400u);
    EXPECT_GE(l.eta, 0.0);
  }
}

TEST(StageProgress, FinishSaysTheLastLineWhenOthersDidTheItems) {
  // An MPI rank sees only its own share of a level: finish() closes the stage all the same.
  Heard heard;
  StageProgress progress({.stage = "parts stitched", .total = 10, .interval = 1e9, .say = heard.sink()});
  progress.advance(3);
  EXPECT_TRUE(heard.text.empty());
  progress.finish();
  progress.finish();
  ASSERT_EQ(heard.text.size(), 1u);
  EXPECT_EQ(heard.read(0).done, 10u);
  EXPECT_EQ(heard.read(0).total, 10u);
}

TEST(StageProgress, TheEtaWeighsTheItemsByTheirWorkWhenTheyDiffer) {
  // Two parts: a small one done, a large one left. Counted alike, the ETA would be the time
  // spent so far (~50 ms: "0 s"); weighed, 99 times it (at least 4.95 s).
  Heard heard;
  StageProgress weighed({.stage = "parts stitched", .total = 2, .total_work = 100, .interval = 0, .say = heard.sink()});
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  weighed.advance(1, 1);
  EXPECT_EQ(weighed.done_work(), 1u);
  weighed.advance(1, 99);
  ASSERT_EQ(heard.text.size(), 2u);
  EXPECT_GE(heard.read(0).eta, 4.0) << heard.text[0];
  EXPECT_EQ(heard.read(1).eta, 0.0) << heard.text[1];

  // Without work the items count alike, as before.
  Heard alike;
  StageProgress counted({.stage = "parts stitched", .total = 100, .interval = 0, .say = alike.sink()});
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  counted.advance(99);
  EXPECT_LT(alike.read(0).eta, 1.0) << alike.text[0];
  EXPECT_EQ(counted.done_work(), 0u);
}

}  // namespace
}  // namespace citymesh
