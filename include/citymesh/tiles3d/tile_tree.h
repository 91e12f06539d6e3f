// SPDX-License-Identifier: MIT
// The level-of-detail tree of a tileset: leaves are the grid tiles of the output; each parent
// merges its (up to four) children and simplifies them with locked borders.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "citymesh/core/mesh.h"
#include "citymesh/tiler/tile_grid.h"
#include "citymesh/tiles3d/simplify.h"

namespace citymesh {

/// The vertex buffer every tile draws from: positions in the tileset's local frame, one source
/// acquisition (feature id) per vertex, and the input's intensity or colour when it has them.
struct TilesetVertices {
  std::vector<Vec3f> positions;
  std::vector<std::uint16_t> feature_ids;
  std::vector<float> intensities;  ///< empty or one per vertex
  std::vector<Rgb8> colors;        ///< empty or one per vertex
};

/// A vertex of a tile: a vertex of the output drawn with one feature id. The same key in two
/// tiles is the same vertex: a parent joining them merges it.
struct TileVertexKey {
  std::uint64_t vertex = 0;
  std::uint16_t feature = 0;
  friend constexpr auto operator<=>(const TileVertexKey&, const TileVertexKey&) = default;
};

/// A tile's mesh, whole: its vertices (keys ascending) with their attributes, and its triangles.
struct TileMesh {
  std::vector<TileVertexKey> keys;
  std::vector<Vec3f> positions;    ///< in the tileset's local frame
  std::vector<float> intensities;  ///< empty or one per vertex
  std::vector<Rgb8> colors;        ///< empty or one per vertex
  std::vector<Triangle> triangles;

  [[nodiscard]] std::size_t vertex_count() const { return keys.size(); }
  /// Appends vertex v of `from` (same attributes); its key must pass every key so far.
  void append_vertex(const TileMesh& from, std::uint32_t v);
};

/// The mesh of one leaf (grid tile), given as the tree needs it; called from several threads
/// at once.
using LeafSource = std::function<TileMesh(const TileKey&)>;

struct TileNode {
  int level = 0;                   ///< 0: leaves; a level-l tile covers 2^l x 2^l grid tiles
  TileKey key;                     ///< grid key at its level: leaf keys shifted right by `level` (see build_tile_tree)
  TileMesh mesh;                   ///< empty once handed to a TileNodeSink
  std::size_t triangle_count = 0;  ///< of its mesh, kept when the mesh is released
  double geometric_error = 0.0;    ///< metres; 0 on leaves, > 0 on parents
  Box3d box;                       ///< local frame: its content and its children's
  std::vector<std::uint32_t> children;
  /// "t<level>_<i>_<j>": the stem of its files.
  [[nodiscard]] std::string name() const;
};

struct TileTree {
  std::vector<TileNode> nodes;  ///< children before their parents; the root is last
  [[nodiscard]] const TileNode& root() const { return nodes.back(); }
};

struct TileTreeParams {
  SimplifyParams simplify;
  double min_geometric_error = 0.001;  ///< metres: a parent's error is never below this
  /// Below the highest level of the grid that still has this many cells holding leaves, each
  /// cell's subtree is built depth first, its leaves one group of four at a time (the cells
  /// run in parallel); the levels above are built level by level. Only the memory and the
  /// order of `TileTree::nodes` depend on it, never the tiles: 1 builds the whole tree depth
  /// first, SIZE_MAX level by level from every leaf at once.
  std::size_t depth_first_cells = 16;
  /// A parent whose simplification with locked borders keeps more triangles than this is
  /// simplified again with only its seams with the neighbouring tiles locked (the vertices the
  /// leaves just outside its cell use too: hole rims and fragments' borders free), and if that
  /// still keeps more, by clustering vertices, each aiming at this many: locked hole rims (MLS
  /// meshes are full of holes) stall the simplifier, and upper tiles then grew with the
  /// output (a 112 M-triangle city's root held 1.06 M triangles). Only a clustered tile may
  /// leave cracks against its neighbours (`citymesh check` measures them).
  std::size_t max_parent_triangles = 262144;
  /// Where parents' simplifications are looked up first and kept after (null: none): a parent
  /// whose children did not change since the run that kept it is not simplified again. Never
  /// changes a tile.
  SimplifyCache* simplified = nullptr;
};

/// Called once per node as soon as the tree no longer reads its mesh (its parent is built, or
/// it is the root), possibly from several threads at once; the mesh is released when it
/// returns. Lets a caller write each tile while the tree is built instead of holding them all.
using TileNodeSink = std::function<void(const TileNode&)>;

/// Builds the tree over the leaves `leaves` (grid keys, ascending, each holding triangles),
/// asking `source` for each leaf's mesh when its subtree is built. Level by level, the nodes without a parent are
/// grouped by their keys one level up and each group gets a parent, except a node alone in its group whose
/// simplification keeps more than half of it: that node is carried up unchanged (a parent would only repeat it) until
/// it meets another, so a parent's children may lie several levels below it. Halving never brings keys of both signs
/// together, so an axis whose leaf keys have both signs (a grid origin inside the output) is counted from its smallest
/// key; node keys and names are then relative to it. The result depends only on the input, never on the thread count.
/// No leaves give an empty tree. Without a sink every node keeps its mesh.
TileTree build_tile_tree(std::span<const TileKey> leaves, const LeafSource& source, const TileTreeParams& params,
                         const TileNodeSink& sink = {});

/// One cell of a tree's lower levels, built on its own (see TileTreeParams::depth_first_cells):
/// its nodes, children before parents (children index this list), every one handed to the
/// sink but the one left open above the cell, whose mesh the levels above still need.
struct TileSubtree {
  std::vector<TileNode> nodes;
  std::uint32_t open = 0;
  bool open_is_final = false;  ///< the open node is a single child that would not simplify alone
};

/// build_tile_tree() in steps, for work shared between processes: the cells below the split
/// level are independent (build_cell() on any thread or process, each with its own sink),
/// and finish() builds the levels above from their subtrees. The same nodes, in the same
/// order, as build_tile_tree(). `source`, `params` and `sink` must outlive it.
class TileTreeBuild {
 public:
  TileTreeBuild(std::span<const TileKey> leaves, const LeafSource& source, const TileTreeParams& params,
                const TileNodeSink& sink = {});
  ~TileTreeBuild();
  TileTreeBuild(const TileTreeBuild&) = delete;
  TileTreeBuild& operator=(const TileTreeBuild&) = delete;

  [[nodiscard]] std::size_t cell_count() const;
  /// The leaves (grid keys, ascending) of cell `c`.
  [[nodiscard]] std::vector<TileKey> cell_leaves(std::size_t c) const;
  /// Cell `c`'s subtree; its nodes go to the sink as they are done. Thread-safe.
  [[nodiscard]] TileSubtree build_cell(std::size_t c) const;
  /// The tree from every cell's subtree (index: cell), built level by level above them.
  [[nodiscard]] TileTree finish(std::vector<TileSubtree> cells) const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

/// The same from one vertex buffer: the triangles (its vertex indices) and each one's leaf
/// key. A leaf's vertices are keyed by their index in the buffer (and its feature id).
TileTree build_tile_tree(const TilesetVertices& vertices, std::span<const Triangle> triangles,
                         std::span<const TileKey> leaf_keys, const TileTreeParams& params,
                         const TileNodeSink& sink = {});

}  // namespace citymesh
