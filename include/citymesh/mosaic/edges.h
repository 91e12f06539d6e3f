// SPDX-License-Identifier: MIT
// Edges of a triangle list by use: which triangles share an edge, which edges are boundary.
// The mosaic's seam terms, stitching and the mosaic's evaluation all start from this.
#pragma once

#include <compare>
#include <cstdint>
#include <span>
#include <vector>

#include "citymesh/core/mesh.h"

namespace citymesh {

/// One use of an edge by a triangle; lo < hi are the edge's vertices.
struct EdgeUse {
  std::uint32_t lo = 0, hi = 0, triangle = 0;
  auto operator<=>(const EdgeUse&) const = default;
};

/// Every edge of every triangle (only those with subset[t] != 0 when a subset is given),
/// sorted: the uses of one edge are adjacent, in triangle order.
std::vector<EdgeUse> edge_uses(std::span<const Triangle> triangles, std::span<const std::uint8_t> subset = {});

/// Calls fn(group) for each edge with the span of its uses, in edge order.
template <class Fn>
void for_each_edge(std::span<const EdgeUse> uses, Fn fn) {
  for (std::size_t i = 0; i < uses.size();) {
    std::size_t j = i + 1;
    while (j < uses.size() && uses[j].lo == uses[i].lo && uses[j].hi == uses[i].hi) ++j;
    fn(uses.subspan(i, j - i));
    i = j;
  }
}

/// The edges used by exactly one triangle, in edge order.
std::vector<EdgeUse> boundary_edges(std::span<const Triangle> triangles);

/// Total length of `edges` on `mesh`'s vertices, summed in their order.
double edges_length(const Mesh& mesh, std::span<const EdgeUse> edges);

}  // namespace citymesh
