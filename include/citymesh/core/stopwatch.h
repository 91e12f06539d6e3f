// SPDX-License-Identifier: MIT
// Wall-clock timing of a stage, for reports and benchmarks.
#pragma once

#include <chrono>

namespace citymesh {

class Stopwatch {
 public:
  /// Seconds since construction or the last restart().
  [[nodiscard]] double seconds() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  }
  /// Returns seconds() and starts counting again (for consecutive stages).
  double restart() {
    const double s = seconds();
    start_ = std::chrono::steady_clock::now();
    return s;
  }

 private:
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
};

}  // namespace citymesh
