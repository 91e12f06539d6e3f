// SPDX-License-Identifier: MIT
// Progress lines of a long stage on stderr: what is done of how many, ETA and memory.
#pragma once

#include <cstdint>
#include <functional>
#include <mutex>
#include <string>

#include "citymesh/core/stopwatch.h"

namespace citymesh {

struct StageProgressParams {
  /// What is counted, as the line starts: "final pass: seam parts stitched".
  std::string stage;
  std::uint64_t total = 0;
  /// What all items cost together, in any unit (bytes, triangles), when they differ in size;
  /// 0: they cost alike. The ETA then assumes the work left goes as fast as the work done.
  std::uint64_t total_work = 0;
  /// Seconds between two lines at least; the line of the last item is always said.
  double interval = 1.0;
  /// Where the lines go; unset: log::info.
  std::function<void(const std::string&)> say = nullptr;
};

/// Says "<stage> <done>/<total>, ETA <s> s, memory <MiB> MiB" as items are done: at most once
/// per interval, and once when the last item is done (or finish() is called), so that a
/// stage of a long run is never silent and a short one says one line. The ETA assumes the
/// items left take as long as those done (or, with a total_work, the work left as long as
/// the work done). Thread-safe.
class StageProgress {
 public:
  explicit StageProgress(StageProgressParams params);

  /// `n` more items done, costing `work` (with a total_work).
  void advance(std::uint64_t n = 1, std::uint64_t work = 0);
  /// Every item done, whoever did them (another process's count is not seen here): says the
  /// last line unless it was said.
  void finish();
  [[nodiscard]] std::uint64_t done() const;
  [[nodiscard]] std::uint64_t done_work() const;

 private:
  /// Under the lock.
  void say_line();

  StageProgressParams params_;
  mutable std::mutex mutex_;
  std::uint64_t done_ = 0, done_work_ = 0;
  bool last_said_ = false;
  Stopwatch clock_, since_line_;
};

}  // namespace citymesh
