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
void build_parent(const TilesetVertices& vertices, const TileTree& tree, TileNode& parent,
                  const TileTreeParams& params) {
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

/// A node that has no parent yet, under its key at the level being built.
struct OpenNode {
  std::uint32_t node;
  TileKey key;
  bool alone_is_final = false;  ///< simplifying it alone was tried and kept too much
};

/// A parent of one child must keep at most this share of the child's triangles: above it, the
/// level repeats its child (once locked borders stop the simplifier, every further level of an
/// isolated street was the same mesh again, encoded again: 18 of a city's 164 tiles).
constexpr double kMaxSingleChildShare = 0.5;

/// Groups the open nodes by their keys one level up and gives each group a parent at `level`
/// (built in parallel); returns the nodes open above it. A node alone in its group whose
/// parent would keep too much of it is carried up instead, marked so that it is not tried
/// alone again (the same mesh simplifies the same way).
std::vector<OpenNode> add_level(const TilesetVertices& vertices, TileTree& tree, std::span<const OpenNode> open,
                                int level, const TileTreeParams& params) {
  std::map<TileKey, std::vector<const OpenNode*>> groups;
  for (const OpenNode& o : open) groups[{o.key.i >> 1, o.key.j >> 1}].push_back(&o);
  // A group of one node already found not to simplify alone gets no parent to try.
  const auto settled_alone = [](const std::vector<const OpenNode*>& members) {
    return members.size() == 1 && members[0]->alone_is_final;
  };
  std::vector<TileNode> parents;
  for (const auto& [key, members] : groups) {
    if (settled_alone(members)) continue;
    std::vector<std::uint32_t> children;
    for (const OpenNode* m : members) children.push_back(m->node);
    parents.push_back({.level = level, .key = key, .mesh = {}, .geometric_error = 0, .box = {},
                       .children = std::move(children)});
  }
  parallel_for_blocks(parents.size(), 1, [&](std::size_t begin, std::size_t end) {
    for (std::size_t p = begin; p < end; ++p) build_parent(vertices, tree, parents[p], params);
  });
  std::vector<OpenNode> above;
  auto parent = parents.begin();
  for (const auto& [key, members] : groups) {
    const OpenNode& first = *members[0];
    if (settled_alone(members)) {
      above.push_back({first.node, key, true});
      continue;
    }
    const double child_triangles = static_cast<double>(tree.nodes[first.node].mesh.triangles.size());
    if (members.size() == 1 &&
        static_cast<double>(parent->mesh.triangles.size()) > kMaxSingleChildShare * child_triangles) {
      above.push_back({first.node, key, true});
    } else {
      above.push_back({static_cast<std::uint32_t>(tree.nodes.size()), key, false});
      tree.nodes.push_back(std::move(*parent));
    }
    ++parent;
  }
  return above;
}

}  // namespace

TileTree build_tile_tree(const TilesetVertices& vertices, std::span<const Triangle> triangles,
                         std::span<const TileKey> leaf_keys, const TileTreeParams& params) {
  TileTree tree;
  // The triangles grouped by leaf as indices (a counting sort), not as copies: a vector of
  // triangles per leaf, grown by doubling, was the peak of a city's export.
  std::map<TileKey, std::uint32_t> leaf_of;
  for (const TileKey& key : leaf_keys) leaf_of.try_emplace(key, 0);
  for (auto& [key, leaf] : leaf_of) {
    leaf = static_cast<std::uint32_t>(tree.nodes.size());
    tree.nodes.push_back({.level = 0, .key = key, .mesh = {}, .geometric_error = 0, .box = {}, .children = {}});
  }
  std::vector<std::uint32_t> start(tree.nodes.size() + 1, 0);
  std::vector<std::uint32_t> leaf_index(triangles.size());
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    // Consecutive triangles mostly share a leaf (the output is in input order): look up only
    // when the key changes.
    leaf_index[t] = t > 0 && leaf_keys[t] == leaf_keys[t - 1] ? leaf_index[t - 1] : leaf_of.at(leaf_keys[t]);
    ++start[leaf_index[t] + 1];
  }
  for (std::size_t n = 0; n < tree.nodes.size(); ++n) start[n + 1] += start[n];
  std::vector<std::uint32_t> order(triangles.size());
  std::vector<std::uint32_t> at(start.begin(), start.end() - 1);
  for (std::size_t t = 0; t < triangles.size(); ++t) order[at[leaf_index[t]]++] = static_cast<std::uint32_t>(t);
  std::vector<std::uint32_t>().swap(leaf_index);
  parallel_for_blocks(tree.nodes.size(), 1, [&](std::size_t begin, std::size_t end) {
    std::vector<Triangle> own;
    for (std::size_t n = begin; n < end; ++n) {
      own.clear();
      for (std::uint32_t i = start[n]; i < start[n + 1]; ++i) own.push_back(triangles[order[i]]);
      TileNode& leaf = tree.nodes[n];
      leaf.mesh = compact(own, vertices.positions.size());
      leaf.box = mesh_box(vertices, leaf.mesh);
    }
  });
  std::vector<std::uint32_t>().swap(order);
  // The nodes still without a parent, with their keys at the level being built.
  std::vector<OpenNode> open;
  for (std::uint32_t n = 0; n < tree.nodes.size(); ++n) open.push_back({n, tree.nodes[n].key, false});
  for (int level = 1; open.size() > 1; ++level) open = add_level(vertices, tree, open, level, params);
  return tree;
}

}  // namespace citymesh
