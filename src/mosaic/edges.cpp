// SPDX-License-Identifier: MIT
#include "citymesh/mosaic/edges.h"

#include <algorithm>

namespace citymesh {

std::vector<EdgeUse> edge_uses(std::span<const Triangle> triangles, std::span<const std::uint8_t> subset) {
  // A counting sort on the lower vertex, then each vertex's few uses (about six) sorted in
  // place: the order std::sort gives, in linear time (the comparison sort of every use was a
  // tenth of the mosaic's energy build).
  const auto wanted = [&](std::uint32_t t) { return subset.empty() || subset[t] != 0; };
  std::uint32_t vertices = 0;
  for (std::uint32_t t = 0; t < triangles.size(); ++t) {
    if (wanted(t)) vertices = std::max({vertices, triangles[t][0] + 1, triangles[t][1] + 1, triangles[t][2] + 1});
  }
  std::vector<std::uint32_t> start(std::size_t{vertices} + 1, 0);
  const auto lower = [&](const Triangle& tri, int k) { return std::min(tri[k], tri[(k + 1) % 3]); };
  for (std::uint32_t t = 0; t < triangles.size(); ++t) {
    if (!wanted(t)) continue;
    for (int k = 0; k < 3; ++k) ++start[lower(triangles[t], k) + 1];
  }
  for (std::size_t v = 0; v < vertices; ++v) start[v + 1] += start[v];
  std::vector<EdgeUse> uses(start[vertices]);
  std::vector<std::uint32_t> next(start.begin(), start.end() - 1);
  for (std::uint32_t t = 0; t < triangles.size(); ++t) {
    if (!wanted(t)) continue;
    const Triangle& tri = triangles[t];
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t u = tri[k], v = tri[(k + 1) % 3];
      uses[next[std::min(u, v)]++] = {std::min(u, v), std::max(u, v), t};
    }
  }
  constexpr std::uint32_t kInsertionSortLimit = 32;  // a fan's centre may have thousands
  for (std::size_t v = 0; v < vertices; ++v) {
    if (start[v + 1] - start[v] > kInsertionSortLimit) {
      std::sort(uses.begin() + start[v], uses.begin() + start[v + 1]);
      continue;
    }
    // Insertion sort: the uses of one vertex are few and already in triangle order.
    for (std::uint32_t i = start[v] + 1; i < start[v + 1]; ++i) {
      const EdgeUse e = uses[i];
      std::uint32_t j = i;
      for (; j > start[v] && e < uses[j - 1]; --j) uses[j] = uses[j - 1];
      uses[j] = e;
    }
  }
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

double edges_length(const Mesh& mesh, std::span<const EdgeUse> edges) {
  double total = 0;
  for (const EdgeUse& e : edges) total += norm(Vec3d(mesh.positions[e.lo]) - Vec3d(mesh.positions[e.hi]));
  return total;
}

}  // namespace citymesh
