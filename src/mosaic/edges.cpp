// SPDX-License-Identifier: MIT
#include "citymesh/mosaic/edges.h"

#include <algorithm>

namespace citymesh {

std::vector<EdgeUse> edge_uses(std::span<const Triangle> triangles, std::span<const std::uint8_t> subset) {
  std::vector<EdgeUse> uses;
  uses.reserve(3 * triangles.size());
  for (std::uint32_t t = 0; t < triangles.size(); ++t) {
    if (!subset.empty() && subset[t] == 0) continue;
    const Triangle& tri = triangles[t];
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t u = tri[k], v = tri[(k + 1) % 3];
      uses.push_back({std::min(u, v), std::max(u, v), t});
    }
  }
  std::sort(uses.begin(), uses.end());
  return uses;
}

std::vector<EdgeUse> boundary_edges(std::span<const Triangle> triangles) {
  const std::vector<EdgeUse> uses = edge_uses(triangles);
  std::vector<EdgeUse> boundary;
  for_each_edge(uses, [&](std::span<const EdgeUse> group) {
    if (group.size() == 1) boundary.push_back(group.front());
  });
  return boundary;
}

}  // namespace citymesh
