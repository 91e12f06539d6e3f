// SPDX-License-Identifier: MIT
#include "citymesh/tiles3d/tile_tree.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <iterator>
#include <map>
#include <numeric>
#include <optional>
#include <utility>

#include "citymesh/core/error.h"
#include "citymesh/core/log.h"
#include "citymesh/core/parallel.h"

namespace citymesh {

std::string TileNode::name() const { return fmt::format("t{}_{}_{}", level, key.i, key.j); }

namespace {

/// A tile mesh from triangles in the buffer's vertex indices: vertices ascending (keyed by
/// their index), triangle order kept. Each thread keeps one slot per buffer vertex (its index
/// in the tile being built, reset after use), so only the tile's distinct vertices are sorted
/// and each corner is found in one step; sorting every corner and binary-searching them was an
/// eighth of the export's time on a city.
TileMesh compact(const TilesetVertices& buffer, std::span<const Triangle> global) {
  constexpr std::uint32_t kAbsent = UINT32_MAX;
  thread_local std::vector<std::uint32_t> slot;
  if (slot.size() < buffer.positions.size()) slot.resize(buffer.positions.size(), kAbsent);
  std::vector<std::uint32_t> vertices;
  for (const Triangle& t : global) {
    for (const std::uint32_t v : t) {
      if (slot[v] == kAbsent) {
        slot[v] = 0;
        vertices.push_back(v);
      }
    }
  }
  std::sort(vertices.begin(), vertices.end());
  TileMesh m;
  for (std::size_t i = 0; i < vertices.size(); ++i) {
    const std::uint32_t v = vertices[i];
    slot[v] = static_cast<std::uint32_t>(i);
    m.keys.push_back({v, buffer.feature_ids[v]});
    m.positions.push_back(buffer.positions[v]);
    if (!buffer.intensities.empty()) m.intensities.push_back(buffer.intensities[v]);
    if (!buffer.colors.empty()) m.colors.push_back(buffer.colors[v]);
  }
  m.triangles.reserve(global.size());
  for (const Triangle& t : global) m.triangles.push_back({slot[t[0]], slot[t[1]], slot[t[2]]});
  for (const std::uint32_t v : vertices) slot[v] = kAbsent;
  return m;
}

/// The triangles `triangles` of `m` (indices into it) on the vertices they use, in key order.
TileMesh subset(const TileMesh& m, std::span<const Triangle> triangles) {
  std::vector<std::uint32_t> local(m.vertex_count(), UINT32_MAX);
  for (const Triangle& t : triangles) {
    for (const std::uint32_t v : t) local[v] = 0;
  }
  TileMesh out;
  for (std::uint32_t v = 0; v < m.vertex_count(); ++v) {
    if (local[v] == UINT32_MAX) continue;
    local[v] = static_cast<std::uint32_t>(out.vertex_count());
    out.append_vertex(m, v);
  }
  for (const Triangle& t : triangles) out.triangles.push_back({local[t[0]], local[t[1]], local[t[2]]});
  return out;
}

/// The meshes as one: each key once (the first mesh's copy), the triangles of each in turn.
TileMesh merge(std::span<const TileMesh* const> meshes) {
  std::vector<TileVertexKey> keys;
  for (const TileMesh* m : meshes) keys.insert(keys.end(), m->keys.begin(), m->keys.end());
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  std::vector<std::pair<const TileMesh*, std::uint32_t>> source(keys.size(), {nullptr, 0});
  std::vector<std::vector<std::uint32_t>> index(meshes.size());
  for (std::size_t k = 0; k < meshes.size(); ++k) {
    const TileMesh& m = *meshes[k];
    std::size_t at = 0;
    for (std::uint32_t v = 0; v < m.vertex_count(); ++v) {
      while (keys[at] != m.keys[v]) ++at;  // both ascend
      index[k].push_back(static_cast<std::uint32_t>(at));
      if (source[at].first == nullptr) source[at] = {&m, v};
    }
  }
  TileMesh out;
  for (const auto& [m, v] : source) out.append_vertex(*m, v);
  for (std::size_t k = 0; k < meshes.size(); ++k) {
    for (const Triangle& t : meshes[k]->triangles)
      out.triangles.push_back({index[k][t[0]], index[k][t[1]], index[k][t[2]]});
  }
  return out;
}

Box3d mesh_box(const TileMesh& m) {
  Box3d box;
  for (const Vec3f& p : m.positions) box.extend(Vec3d(p));
  return box;
}

/// What one build shares: the leaves and the caller's settings.
struct TreeBuild {
  std::vector<TileKey> leaves;  ///< ascending, less `offset`
  TileKey offset;               ///< what was subtracted from the grid's keys (see key_offset)
  const LeafSource& source;
  const TileTreeParams& params;
  const TileNodeSink& sink;
};

/// Which vertices of `whole`, the merged mesh of `parent`'s cell, the leaves around the cell
/// use too: the cell's seams with its neighbours, which a parent must keep in place to meet
/// them. Triangles are far smaller than a grid tile, so only the ring of leaves just outside
/// the cell can share a vertex with it; they are read again here (only for capped parents).
std::vector<std::uint8_t> shared_with_neighbours(const TreeBuild& b, const TileNode& parent, const TileMesh& whole) {
  const std::int64_t side = std::int64_t{1} << parent.level;
  const std::int64_t i0 = parent.key.i * side - 1, i1 = (parent.key.i + 1) * side;
  const std::int64_t j0 = parent.key.j * side - 1, j1 = (parent.key.j + 1) * side;
  std::vector<std::uint64_t> around;
  for (const TileKey& leaf : b.leaves) {
    const bool near = leaf.i >= i0 && leaf.i <= i1 && leaf.j >= j0 && leaf.j <= j1;
    const bool inside = leaf.i > i0 && leaf.i < i1 && leaf.j > j0 && leaf.j < j1;
    if (!near || inside) continue;
    const TileMesh m = b.source({leaf.i + b.offset.i, leaf.j + b.offset.j});
    for (const TileVertexKey& k : m.keys) around.push_back(k.vertex);
  }
  std::sort(around.begin(), around.end());
  std::vector<std::uint8_t> shared(whole.vertex_count(), 0);
  for (std::size_t v = 0; v < shared.size(); ++v) {
    shared[v] = std::binary_search(around.begin(), around.end(), whole.keys[v].vertex) ? 1 : 0;
  }
  return shared;
}

/// Merges the children's meshes (children index `nodes`) and simplifies the result with
/// locked borders.
void build_parent(const TreeBuild& b, std::span<const TileNode> nodes, TileNode& parent) {
  const TileTreeParams& params = b.params;
  std::vector<const TileMesh*> children;
  double child_error = 0.0;
  for (const std::uint32_t c : parent.children) {
    children.push_back(&nodes[c].mesh);
    child_error = std::max(child_error, nodes[c].geometric_error);
    parent.box.extend(nodes[c].box);
  }
  const TileMesh whole = merge(children);
  SimplifiedMesh simplified = simplify_mesh_kept(params.simplified, whole.positions, whole.triangles, params.simplify);
  // Past the cap: only the seams with the neighbouring tiles locked (hole rims and the
  // borders of fragments free), then vertices clustered whatever the error (non-manifold
  // pieces and errors beyond the bound stop edge collapses; the cap is what bounds a tile's
  // memory, and the tile's geometric error tells viewers what it cost), each aiming at the cap.
  SimplifyParams looser = params.simplify;
  looser.target_ratio = static_cast<double>(params.max_parent_triangles) / static_cast<double>(whole.triangles.size());
  looser.lock_border = false;
  looser.weld = true;
  for (const bool sloppy : {false, true}) {
    if (simplified.triangles.size() <= params.max_parent_triangles) break;
    looser.sloppy = sloppy;
    if (sloppy) looser.max_error_fraction = 1.0;
    const std::vector<std::uint8_t> seams =
        sloppy ? std::vector<std::uint8_t>{} : shared_with_neighbours(b, parent, whole);
    const std::size_t before = simplified.triangles.size();
    simplified = simplify_mesh_kept(params.simplified, whole.positions, whole.triangles, looser, seams);
    log::debug("3D Tiles: {} of {} triangles past the cap of {}: {} -> {} triangles {}", parent.name(),
               whole.triangles.size(), params.max_parent_triangles, before, simplified.triangles.size(),
               sloppy ? std::string("by clustering (its seams may crack)")
                      : fmt::format("with {} seam vertices locked", std::count(seams.begin(), seams.end(), 1)));
  }
  parent.mesh = subset(whole, simplified.triangles);
  parent.triangle_count = parent.mesh.triangles.size();
  parent.geometric_error = std::max(child_error + simplified.error, params.min_geometric_error);
}

/// A node that has no parent yet, under its key at the level being built.
struct OpenNode {
  std::uint32_t node;
  TileKey key;
  bool alone_is_final = false;  ///< simplifying it alone was tried and kept too much
};

/// The open nodes whose keys one level up are the same, in key order.
using Group = std::vector<OpenNode>;

/// A parent of one child must keep at most this share of the child's triangles: above it, the
/// level repeats its child (once locked borders stop the simplifier, every further level of an
/// isolated street was the same mesh again, encoded again: 18 of a city's 164 tiles).
constexpr double kMaxSingleChildShare = 0.5;

/// A group of one node already found not to simplify alone gets no parent to try (the same
/// mesh simplifies the same way).
bool settled_alone(const Group& g) { return g.size() == 1 && g[0].alone_is_final; }

/// What the tree subtracts from the leaf keys. Halving never brings a negative key and a
/// non-negative one together (-1 stays -1, 0 stays 0), so an axis whose keys have both signs
/// (a grid origin inside the output) is counted from its smallest key; otherwise the keys are
/// the grid's own.
TileKey key_offset(std::span<const TileKey> leaf_keys) {
  if (leaf_keys.empty()) return {};
  std::int64_t lo_i = leaf_keys[0].i, hi_i = lo_i, lo_j = leaf_keys[0].j, hi_j = lo_j;
  for (const TileKey& k : leaf_keys) {
    lo_i = std::min<std::int64_t>(lo_i, k.i);
    hi_i = std::max<std::int64_t>(hi_i, k.i);
    lo_j = std::min<std::int64_t>(lo_j, k.j);
    hi_j = std::max<std::int64_t>(hi_j, k.j);
  }
  if (hi_i - lo_i > INT32_MAX || hi_j - lo_j > INT32_MAX) {
    throw ProcessingError(fmt::format("3D Tiles: the output spans more than 2^31 grid tiles ({} x {})", hi_i - lo_i + 1,
                                      hi_j - lo_j + 1));
  }
  const auto from = [](std::int64_t lo, std::int64_t hi) {
    return lo < 0 && hi >= 0 ? static_cast<std::int32_t>(lo) : 0;
  };
  return {from(lo_i, hi_i), from(lo_j, hi_j)};
}

TileNode make_leaf(const TreeBuild& b, std::uint32_t leaf) {
  TileNode node;
  node.key = b.leaves[leaf];
  node.mesh = b.source({node.key.i + b.offset.i, node.key.j + b.offset.j});
  node.triangle_count = node.mesh.triangles.size();
  node.box = mesh_box(node.mesh);
  return node;
}

/// Hands a node the tree is done with to the sink, then frees its mesh.
void hand_over(const TreeBuild& b, TileNode& node) {
  if (!b.sink) return;
  b.sink(node);
  node.mesh = TileMesh{};
}

/// The group's parent at `level`, built from `nodes`; none when it would only repeat the
/// group's single node, which is then carried up instead. The children of a parent that is
/// kept are handed over.
std::optional<TileNode> parent_of(const TreeBuild& b, std::span<TileNode> nodes, const Group& g, int level,
                                  TileKey key) {
  TileNode parent;
  parent.level = level;
  parent.key = key;
  for (const OpenNode& o : g) parent.children.push_back(o.node);
  build_parent(b, nodes, parent);
  const auto child_triangles = static_cast<double>(nodes[g[0].node].triangle_count);
  if (g.size() == 1 && static_cast<double>(parent.triangle_count) > kMaxSingleChildShare * child_triangles) {
    return std::nullopt;
  }
  for (const std::uint32_t c : parent.children) hand_over(b, nodes[c]);
  return parent;
}

/// The group's node open above it under `key`: its parent, appended to `nodes`, or without
/// one the group's single node, carried up.
OpenNode open_above(std::vector<TileNode>& nodes, std::optional<TileNode> parent, const Group& g, TileKey key) {
  if (!parent) return {g[0].node, key, true};
  nodes.push_back(std::move(*parent));
  return {static_cast<std::uint32_t>(nodes.size() - 1), key, false};
}

/// Settles one group at `level` in `nodes`: appends its parent, or carries its node up.
OpenNode settle(const TreeBuild& b, std::vector<TileNode>& nodes, const Group& g, int level, TileKey key) {
  std::optional<TileNode> parent = settled_alone(g) ? std::nullopt : parent_of(b, nodes, g, level, key);
  return open_above(nodes, std::move(parent), g, key);
}

/// The subtree of the cell `key` at `level` holding the leaves `leaves` (ascending), depth
/// first: each quarter's subtree is finished, and its nodes handed over, before the next one
/// is read. Appends its nodes to `nodes` (children first) and returns the node left open.
OpenNode build_cell_tree(const TreeBuild& b, std::span<const std::uint32_t> leaves, int level, TileKey key,
                         std::vector<TileNode>& nodes) {
  if (level == 0) {
    nodes.push_back(make_leaf(b, leaves[0]));
    return {static_cast<std::uint32_t>(nodes.size() - 1), key, false};
  }
  // The quarters in key order: (i, j) ascending, as the level-by-level grouping meets them.
  std::array<std::vector<std::uint32_t>, 4> quarters;
  for (const std::uint32_t leaf : leaves) {
    const TileKey k = b.leaves[leaf];
    quarters[((k.i >> (level - 1)) & 1) * 2 + ((k.j >> (level - 1)) & 1)].push_back(leaf);
  }
  Group members;
  for (const std::vector<std::uint32_t>& q : quarters) {
    if (q.empty()) continue;
    const TileKey leaf = b.leaves[q[0]];
    members.push_back(build_cell_tree(b, q, level - 1, {leaf.i >> (level - 1), leaf.j >> (level - 1)}, nodes));
  }
  return settle(b, nodes, members, level, key);
}

/// Groups the open nodes by their keys one level up and gives each group a parent at `level`
/// (built in parallel); returns the nodes open above it.
std::vector<OpenNode> add_level(const TreeBuild& b, TileTree& tree, std::span<const OpenNode> open, int level) {
  std::map<TileKey, Group> groups;
  for (const OpenNode& o : open) groups[{o.key.i >> 1, o.key.j >> 1}].push_back(o);
  const std::vector<std::pair<TileKey, Group>> listed(std::make_move_iterator(groups.begin()),
                                                      std::make_move_iterator(groups.end()));
  std::vector<std::optional<TileNode>> parents(listed.size());
  parallel_for_blocks(listed.size(), 1, [&](std::size_t begin, std::size_t end) {
    for (std::size_t p = begin; p < end; ++p) {
      const auto& [key, members] = listed[p];
      if (!settled_alone(members)) parents[p] = parent_of(b, tree.nodes, members, level, key);
    }
  });
  std::vector<OpenNode> above;
  for (std::size_t p = 0; p < listed.size(); ++p) {
    above.push_back(open_above(tree.nodes, std::move(parents[p]), listed[p].second, listed[p].first));
  }
  return above;
}

/// The level whose one cell holds every leaf: the tree's top.
int top_level(std::span<const TileKey> leaves) {
  int level = 0;
  const auto one_cell = [&](int l) {
    return std::all_of(leaves.begin(), leaves.end(), [&](const TileKey& k) {
      return (k.i >> l) == (leaves[0].i >> l) && (k.j >> l) == (leaves[0].j >> l);
    });
  };
  while (!one_cell(level)) ++level;
  return level;
}

/// The leaves (ascending) of every cell at `level` holding any, in key order.
std::map<TileKey, std::vector<std::uint32_t>> cells_at(std::span<const TileKey> leaves, int level) {
  std::map<TileKey, std::vector<std::uint32_t>> cells;
  for (std::uint32_t n = 0; n < leaves.size(); ++n) {
    cells[{leaves[n].i >> level, leaves[n].j >> level}].push_back(n);
  }
  return cells;
}

/// The cells built depth first: those of the highest level up to `top` with at least
/// `count` cells holding leaves (level 0, the leaves, when none has), listed in key order.
struct DepthFirstCells {
  int level = 0;
  std::vector<std::pair<TileKey, std::vector<std::uint32_t>>> cells;
};

DepthFirstCells depth_first_cells(std::span<const TileKey> leaves, int top, std::size_t count) {
  int level = top;
  auto cells = cells_at(leaves, level);
  while (level > 0 && cells.size() < count) cells = cells_at(leaves, --level);
  return {level, {std::make_move_iterator(cells.begin()), std::make_move_iterator(cells.end())}};
}

}  // namespace

struct TileTreeBuild::State {
  TreeBuild b;
  int split = 0;  ///< the level of the cells' tops
  std::vector<std::pair<TileKey, std::vector<std::uint32_t>>> cells;
};

TileTreeBuild::TileTreeBuild(std::span<const TileKey> leaves, const LeafSource& source, const TileTreeParams& params,
                             const TileNodeSink& sink)
    : state_(std::make_unique<State>(
          State{.b = {.leaves = {}, .offset = key_offset(leaves), .source = source, .params = params, .sink = sink},
                .split = 0,
                .cells = {}})) {
  TreeBuild& b = state_->b;
  for (const TileKey& k : leaves) b.leaves.push_back({k.i - b.offset.i, k.j - b.offset.j});
  if (b.leaves.empty()) return;
  auto [split, listed] =
      depth_first_cells(b.leaves, top_level(b.leaves), std::max<std::size_t>(params.depth_first_cells, 1));
  state_->split = split;
  state_->cells = std::move(listed);
}

TileTreeBuild::~TileTreeBuild() = default;

std::size_t TileTreeBuild::cell_count() const { return state_->cells.size(); }

std::vector<TileKey> TileTreeBuild::cell_leaves(std::size_t c) const {
  const TreeBuild& b = state_->b;
  std::vector<TileKey> out;
  for (const std::uint32_t leaf : state_->cells.at(c).second) {
    out.push_back({b.leaves[leaf].i + b.offset.i, b.leaves[leaf].j + b.offset.j});
  }
  return out;
}

TileSubtree TileTreeBuild::build_cell(std::size_t c) const {
  const auto& [key, leaves] = state_->cells.at(c);
  TileSubtree out;
  const OpenNode open = build_cell_tree(state_->b, leaves, state_->split, key, out.nodes);
  out.open = open.node;
  out.open_is_final = open.alone_is_final;
  return out;
}

TileTree TileTreeBuild::finish(std::vector<TileSubtree> cells) const {
  const TreeBuild& b = state_->b;
  TileTree tree;
  if (b.leaves.empty()) return tree;
  if (cells.size() != state_->cells.size()) {
    throw ProcessingError(fmt::format("3D Tiles: {} subtrees for {} cells", cells.size(), state_->cells.size()));
  }
  // Each cell's nodes appended in key order.
  std::vector<OpenNode> open;
  for (std::size_t c = 0; c < cells.size(); ++c) {
    const auto at = static_cast<std::uint32_t>(tree.nodes.size());
    if (cells[c].open >= cells[c].nodes.size())
      throw ProcessingError("3D Tiles: a subtree's open node is not one of its nodes");
    for (TileNode& node : cells[c].nodes) {
      for (std::uint32_t& child : node.children) child += at;
      tree.nodes.push_back(std::move(node));
    }
    open.push_back({cells[c].open + at, state_->cells[c].first, cells[c].open_is_final});
  }
  // Above them, level by level.
  for (int level = state_->split + 1; open.size() > 1; ++level) open = add_level(b, tree, open, level);
  hand_over(b, tree.nodes[open[0].node]);
  return tree;
}

TileTree build_tile_tree(std::span<const TileKey> leaves, const LeafSource& source, const TileTreeParams& params,
                         const TileNodeSink& sink) {
  const TileTreeBuild build(leaves, source, params, sink);
  std::vector<TileSubtree> cells(build.cell_count());
  parallel_for_blocks(cells.size(), 1, [&](std::size_t begin, std::size_t end) {
    for (std::size_t c = begin; c < end; ++c) cells[c] = build.build_cell(c);
  });
  return build.finish(std::move(cells));
}

TileTree build_tile_tree(const TilesetVertices& vertices, std::span<const Triangle> triangles,
                         std::span<const TileKey> leaf_keys, const TileTreeParams& params, const TileNodeSink& sink) {
  // The triangles grouped by leaf as indices (a counting sort), not as copies: a vector of
  // triangles per leaf, grown by doubling, was the peak of a city's export.
  std::map<TileKey, std::uint32_t> leaf_of;
  for (const TileKey& key : leaf_keys) leaf_of.try_emplace(key, 0);
  std::vector<TileKey> leaves;
  for (auto& [key, leaf] : leaf_of) {
    leaf = static_cast<std::uint32_t>(leaves.size());
    leaves.push_back(key);
  }
  std::vector<std::uint32_t> start(leaves.size() + 1, 0), leaf_index(leaf_keys.size());
  for (std::size_t t = 0; t < leaf_keys.size(); ++t) {
    // Consecutive triangles mostly share a leaf (the output is in input order): look up only
    // when the key changes.
    leaf_index[t] = t > 0 && leaf_keys[t] == leaf_keys[t - 1] ? leaf_index[t - 1] : leaf_of.at(leaf_keys[t]);
    ++start[leaf_index[t] + 1];
  }
  for (std::size_t n = 0; n < leaves.size(); ++n) start[n + 1] += start[n];
  std::vector<std::uint32_t> order(leaf_keys.size());
  std::vector<std::uint32_t> at(start.begin(), start.end() - 1);
  for (std::size_t t = 0; t < leaf_keys.size(); ++t) order[at[leaf_index[t]]++] = static_cast<std::uint32_t>(t);
  const LeafSource from_buffer = [&](const TileKey& key) {
    const std::uint32_t leaf = leaf_of.at(key);
    std::vector<Triangle> own;
    own.reserve(start[leaf + 1] - start[leaf]);
    for (std::uint32_t i = start[leaf]; i < start[leaf + 1]; ++i) own.push_back(triangles[order[i]]);
    return compact(vertices, own);
  };
  return build_tile_tree(leaves, from_buffer, params, sink);
}

void TileMesh::append_vertex(const TileMesh& from, std::uint32_t v) {
  keys.push_back(from.keys[v]);
  positions.push_back(from.positions[v]);
  if (!from.intensities.empty()) intensities.push_back(from.intensities[v]);
  if (!from.colors.empty()) colors.push_back(from.colors[v]);
}

}  // namespace citymesh
