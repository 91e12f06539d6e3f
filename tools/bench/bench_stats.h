// SPDX-License-Identifier: MIT
// What the benchmarks judge their targets on: single runs on this shared VM vary by +-10 %
// (and a file read by up to 4x), so they repeat and take the median.
#pragma once

#include <algorithm>
#include <vector>

namespace citymesh::bench {

/// The median of `values` (the upper middle one for an even count); 0 when empty.
inline double median(std::vector<double> values) {
  if (values.empty()) return 0;
  const auto middle = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), middle, values.end());
  return *middle;
}

}  // namespace citymesh::bench
