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

/// A tile mesh from triangles in global vertex indices: vertices ascending, triangle order kept.
TileMesh compact(std::span<const Triangle> global) {
  TileMesh m;
  m.vertices.reserve(global.size() * 3);
  for (const Triangle& t : global) m.vertices.insert(m.vertices.end(), t.begin(), t.end());
  std::sort(m.vertices.begin(), m.vertices.end());
  m.vertices.erase(std::unique(m.vertices.begin(), m.vertices.end()), m.vertices.end());
  m.triangles.reserve(global.size());
  auto local = [&](std::uint32_t v) {
    return static_cast<std::uint32_t>(std::lower_bound(m.vertices.begin(), m.vertices.end(), v) - m.vertices.begin());
  };
  for (const Triangle& t : global) m.triangles.push_back({local(t[0]), local(t[1]), local(t[2])});
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
  const TileMesh whole = compact(merged);
  std::vector<Vec3f> positions;
  positions.reserve(whole.vertices.size());
  for (const std::uint32_t v : whole.vertices) positions.push_back(vertices.positions[v]);
  const SimplifiedMesh simplified = simplify_mesh(positions, whole.triangles, params.simplify);
  std::vector<Triangle> kept;
  kept.reserve(simplified.triangles.size());
  for (const Triangle& t : simplified.triangles) {
    kept.push_back({whole.vertices[t[0]], whole.vertices[t[1]], whole.vertices[t[2]]});
  }
  parent.mesh = compact(kept);
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
      leaf.mesh = compact(leaves.at(leaf.key));
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
