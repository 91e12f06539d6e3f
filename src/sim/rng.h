// SPDX-License-Identifier: MIT
// A small, fully specified random generator (SplitMix64): the same seed gives the same scene
// and scans on every platform and standard library, unlike std:: distributions.
#pragma once

#include <cmath>
#include <cstdint>

namespace citymesh::sim {

class Rng {
 public:
  explicit Rng(std::uint64_t seed) : state_(seed) {}
  std::uint64_t next() {
    std::uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  /// Uniform in [0, 1).
  double unit() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }
  float uniform(float lo, float hi) { return lo + static_cast<float>(unit()) * (hi - lo); }
  int integer(int lo, int hi) { return lo + static_cast<int>(unit() * (hi - lo + 1)); }
  /// Standard normal (Box-Muller).
  double normal() {
    const double u1 = 1.0 - unit(), u2 = unit();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
  }

 private:
  std::uint64_t state_;
};

}  // namespace citymesh::sim
