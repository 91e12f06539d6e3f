// SPDX-License-Identifier: MIT
// Minimum s-t cut / maximum flow on a directed graph with real capacities: our own
// Boykov-Kolmogorov algorithm (two search trees grown from the terminals and kept between
// augmentations; orphans re-adopted), the engine under the mosaic's QPBO.
#pragma once

#include <cstdint>
#include <vector>

namespace citymesh {

class MaxFlow {
 public:
  using Node = std::uint32_t;

  explicit MaxFlow(std::size_t nodes = 0);

  /// Adds a node and returns its index.
  Node add_node();
  [[nodiscard]] std::size_t node_count() const { return nodes_.size(); }

  /// Makes room for this many more edges (add_edge calls).
  void reserve_edges(std::size_t edges) { staged_.reserve(staged_.size() + 2 * edges); }

  /// Adds capacity from the source to i and from i to the sink (both >= 0, accumulated).
  void add_terminal(Node i, double from_source, double to_sink);
  /// Adds an arc i -> j of capacity `cap` and its reverse j -> i of capacity `rev_cap`
  /// (both >= 0). i != j.
  void add_edge(Node i, Node j, double cap, double rev_cap);

  /// Computes a maximum flow and returns its value. Call once, after every node and edge
  /// (it lays the arcs out for the search; a second call or a later edge throws).
  double solve();

  /// After solve(): the nodes reachable from the source in the residual graph (the source side
  /// of the minimum cut that is smallest on the source side), one flag per node. Residuals
  /// below 1e-12 of the largest capacity count as zero (rounding left by the pushes).
  [[nodiscard]] std::vector<std::uint8_t> source_side() const;

  /// Path augmentations made by solve(), for benchmarks.
  [[nodiscard]] std::uint64_t augmentations() const { return augmentations_; }

 private:
  using Arc = std::uint32_t;
  static constexpr Arc kNone = UINT32_MAX;
  static constexpr Arc kTerminal = UINT32_MAX - 1;  ///< parent of a node hanging from its terminal
  static constexpr Arc kOrphan = UINT32_MAX - 2;

  enum class Tree : std::uint8_t { free, source, sink };

  /// 32 bytes, aligned: two nodes to a cache line, none across two (the search waits on
  /// memory: 40 bytes, with the end of the arcs stored, took ~10 % longer).
  struct alignas(32) NodeData {
    Arc first = 0;       ///< outgoing arcs: [first, arcs_end(i)) once solve() has laid them out
    Arc parent = kNone;  ///< arc from the node to its parent (towards the terminal)
    Node next_active = 0;
    std::uint32_t stamp = 0, distance = 0;  ///< distance-to-terminal heuristic, valid at `stamp`
    bool active = false;
    Tree tree = Tree::free;
    double terminal = 0;  ///< residual: > 0 from the source, < 0 to the sink
  };
  static_assert(sizeof(NodeData) == 32);
  /// An arc as added: arcs come in pairs, the reverse of arc a is a ^ 1.
  struct StagedArc {
    Node head = 0;
    double capacity = 0;
  };
  /// An arc as solved: the arcs out of one node are contiguous (a cache line holds several
  /// of them, where a linked list would jump), each knows its reverse.
  struct ArcData {
    Node head = 0;
    Arc reverse = 0;
    double residual = 0;
  };

  void lay_out_arcs();
  /// One past node i's last outgoing arc (the arcs are laid out node after node).
  [[nodiscard]] Arc arcs_end(Node i) const {
    return i + 1 < nodes_.size() ? nodes_[i + 1].first : static_cast<Arc>(arcs_.size());
  }
  void push_two_arc_paths();
  void set_active(Node i);
  Node next_active();
  bool grow(Node i, Arc& bridge);
  void augment(Arc bridge);
  void adopt(Node i);
  [[nodiscard]] bool rooted(Node i, std::uint32_t& distance);

  std::vector<NodeData> nodes_;
  std::vector<StagedArc> staged_;
  std::vector<ArcData> arcs_;
  std::vector<Node> orphans_;
  Node active_first_ = 0, active_last_ = 0;
  bool have_active_ = false;
  std::uint32_t time_ = 0;
  double flow_ = 0;
  double largest_ = 0;  ///< largest capacity given
  double zero_ = 0;     ///< residuals at or below this count as saturated
  static constexpr double kRelativeZero = 1e-12;
  std::uint64_t augmentations_ = 0;
  bool solved_ = false;
};

}  // namespace citymesh
