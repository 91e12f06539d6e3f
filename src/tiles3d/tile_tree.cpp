// SPDX-License-Identifier: MIT
#include "citymesh/tiles3d/tile_tree.h"

#include <fmt/format.h>

#include <algorithm>
#include <map>
#include <numeric>

#include "citymesh/core/parallel.h"

namespace citymesh {

std::string TileNode::name() const { return fmt::format("t{}_{}_{}", level, key.i, key.j); }

namespace {

/// A tile mesh from triangles in global vertex indices (< vertex_count): vertices ascending,
/// triangle order kept. Each thread keeps one slot per global vertex (its index in the tile
/// being built, reset after use), so only the tile's distinct vertices are sorted and each
/// corner is found in one step; sorting every corner and binary-searching them was an eighth
/// of the export's time on a city.
TileMesh compact(std::span<const Triangle> global, std::size_t vertex_count) {
  constexpr std::uint32_t kAbsent = UINT32_MAX;
  thread_local std::vector<std::uint32_t> slot;
  if (slot.size() < vertex_count) slot.resize(vertex_count, kAbsent);
  TileMesh m;
  m.triangles.reserve(global.size());
  for (const Triangle& t : global) {
    for (const std::uint32_t v : t) {
      if (slot[v] == kAbsent) {
        slot[v] = 0;
        m.vertices.push_back(v);
      }
    }
  }
  std::sort(m.vertices.begin(), m.vertices.end());
  for (std::size_t i = 0; i < m.vertices.size(); ++i) slot[m.vertices[i]] = static_cast<std::uint32_t>(i);
  for (const Triangle& t : global) m.triangles.push_back({slot[t[0]], slot[t[1]], slot[t[2]]});
  for (const std::uint32_t v : m.vertices) slot[v] = kAbsent;
  return m;
}

std::vector<Triangle> to_global(const TileMesh& m) {
  std::vector<Triangle> out;
  out.reserve(m.triangles.size());
  for (const Triangle& t : m.triangles) out.push_back({m.vertices[t[0]], m.vertices[t[1]], m.vertices[t[2]]});
  return out;
}

Box3d mesh_box(const TilesetVertices& vertices, const TileMesh& m) {
  Box3d box;
  for (const std::uint32_t v : m.vertices) box.extend(Vec3d(vertices.positions[v]));
  return box;
}

/// Merges the children's meshes and simplifies the result with locked borders.
void build_parent(const TilesetVertices& vertices, TileTree& tree, TileNode& parent, const TileTreeParams& params) {
  std::vector<Triangle> merged;
  double child_error = 0.0;
  for (const std::uint32_t c : parent.children) {
    const std::vector<Triangle> g = to_global(tree.nodes[c].mesh);
    merged.insert(merged.end(), g.begin(), g.end());
    child_error = std::max(child_error, tree.nodes[c].geometric_error);
    parent.box.extend(tree.nodes[c].box);
  }
  const TileMesh whole = compact(merged, vertices.positions.size());
  std::vector<Vec3f> positions;
  positions.reserve(whole.vertices.size());
  for (const std::uint32_t v : whole.vertices) positions.push_back(vertices.positions[v]);
  const SimplifiedMesh simplified = simplify_mesh(positions, whole.triangles, params.simplify);
  std::vector<Triangle> kept;
  kept.reserve(simplified.triangles.size());
  for (const Triangle& t : simplified.triangles) {
    kept.push_back({whole.vertices[t[0]], whole.vertices[t[1]], whole.vertices[t[2]]});
  }
  parent.mesh = compact(kept, vertices.positions.size());
  parent.geometric_error = std::max(child_error + simplified.error, params.min_geometric_error);
}

}  // namespace

TileTree build_tile_tree(const TilesetVertices& vertices, std::span<const Triangle> triangles,
                         std::span<const TileKey> leaf_keys, const TileTreeParams& params) {
  TileTree tree;
  std::map<TileKey, std::vector<Triangle>> leaves;
  for (std::size_t t = 0; t < triangles.size(); ++t) leaves[leaf_keys[t]].push_back(triangles[t]);
  for (auto& [key, tris] : leaves) tree.nodes.push_back({.level = 0, .key = key, .mesh = {}, .geometric_error = 0,
                                                         .box = {}, .children = {}});
  parallel_for_blocks(tree.nodes.size(), 1, [&](std::size_t begin, std::size_t end) {
    for (std::size_t n = begin; n < end; ++n) {
      TileNode& leaf = tree.nodes[n];
      leaf.mesh = compact(leaves.at(leaf.key), vertices.positions.size());
      leaf.box = mesh_box(vertices, leaf.mesh);
    }
  });
  std::size_t level_begin = 0;
  for (int level = 1; tree.nodes.size() - level_begin > 1; ++level) {
    std::map<TileKey, std::vector<std::uint32_t>> parents;
    for (std::size_t n = level_begin; n < tree.nodes.size(); ++n) {
      const TileKey k = tree.nodes[n].key;
      parents[{k.i >> 1, k.j >> 1}].push_back(static_cast<std::uint32_t>(n));
    }
    level_begin = tree.nodes.size();
    for (auto& [key, children] : parents) {
      tree.nodes.push_back({.level = level, .key = key, .mesh = {}, .geometric_error = 0, .box = {},
                            .children = std::move(children)});
    }
    const std::size_t count = tree.nodes.size() - level_begin;
    parallel_for_blocks(count, 1, [&](std::size_t begin, std::size_t end) {
      for (std::size_t n = begin; n < end; ++n) build_parent(vertices, tree, tree.nodes[level_begin + n], params);
    });
  }
  return tree;
}

}  // namespace citymesh
