// SPDX-License-Identifier: MIT
// Boykov-Kolmogorov max-flow (Boykov & Kolmogorov, "An experimental comparison of min-cut/
// max-flow algorithms for energy minimization in vision", PAMI 2004), written from the paper:
// a search tree grows from each terminal; when they meet, the path is augmented; nodes cut
// from their tree by saturated arcs (orphans) look for a new parent in the same tree or
// become free. The trees are kept between augmentations, which is what makes it fast on the
// grid-like graphs of image and mesh labelling.
#include "citymesh/mosaic/max_flow.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "citymesh/core/error.h"

namespace citymesh {

MaxFlow::MaxFlow(std::size_t nodes) : nodes_(nodes) {}

MaxFlow::Node MaxFlow::add_node() {
  nodes_.emplace_back();
  return static_cast<Node>(nodes_.size() - 1);
}

void MaxFlow::add_terminal(Node i, double from_source, double to_sink) {
  // Fold the node's current net capacity into the new pair, push the common part straight
  // through (it is flow s -> i -> t whatever the cut) and keep the difference.
  NodeData& n = nodes_[i];
  if (n.terminal > 0) {
    from_source += n.terminal;
  } else {
    to_sink -= n.terminal;
  }
  flow_ += std::min(from_source, to_sink);
  n.terminal = from_source - to_sink;
  largest_ = std::max(largest_, std::abs(n.terminal));
}

void MaxFlow::add_edge(Node i, Node j, double cap, double rev_cap) {
  if (i == j) throw ProcessingError("max-flow: an edge from a node to itself");
  if (solved_) throw ProcessingError("max-flow: an edge added after solve()");
  largest_ = std::max({largest_, cap, rev_cap});
  if (staged_.size() + 2 >= kOrphan) throw ProcessingError("max-flow: too many edges");
  staged_.push_back({j, cap});
  staged_.push_back({i, rev_cap});
}

void MaxFlow::lay_out_arcs() {
  // Counting sort by tail (the tail of arc a is the head of a ^ 1). Within a node, the arcs
  // keep the order of the linked lists this layout replaced: the last added first.
  std::vector<Arc> next(nodes_.size() + 1, 0);
  for (std::size_t a = 0; a < staged_.size(); ++a) ++next[staged_[a ^ 1].head + 1];
  for (std::size_t i = 0; i < nodes_.size(); ++i) {
    next[i + 1] += next[i];
    nodes_[i].first = next[i];
  }
  std::vector<Arc> position(staged_.size());
  for (std::size_t a = staged_.size(); a-- > 0;) position[a] = next[staged_[a ^ 1].head]++;
  arcs_.resize(staged_.size());
  for (std::size_t a = 0; a < staged_.size(); ++a)
    arcs_[position[a]] = {staged_[a].head, position[a ^ 1], staged_[a].capacity};
  staged_ = {};
}

void MaxFlow::set_active(Node i) {
  NodeData& n = nodes_[i];
  if (n.active) return;
  n.active = true;
  if (have_active_) {
    nodes_[active_last_].next_active = i;
  } else {
    active_first_ = i;
    have_active_ = true;
  }
  active_last_ = i;
}

MaxFlow::Node MaxFlow::next_active() {
  while (have_active_) {
    const Node i = active_first_;
    NodeData& n = nodes_[i];
    if (i == active_last_) {
      have_active_ = false;
    } else {
      active_first_ = n.next_active;
    }
    n.active = false;
    if (n.tree != Tree::free) return i;
  }
  return std::numeric_limits<Node>::max();
}

bool MaxFlow::grow(Node i, Arc& bridge) {
  const NodeData& ni = nodes_[i];
  const bool source = ni.tree == Tree::source;
  for (Arc a = ni.first, end = arcs_end(i); a < end; ++a) {
    // Source tree: grow along i -> j. Sink tree: along j -> i (the reverse arc).
    if (!((source ? arcs_[a].residual : arcs_[arcs_[a].reverse].residual) > zero_)) continue;
    const Node j = arcs_[a].head;
    NodeData& nj = nodes_[j];
    if (nj.tree == Tree::free) {
      nj.tree = ni.tree;
      nj.parent = arcs_[a].reverse;
      nj.stamp = ni.stamp;
      nj.distance = ni.distance + 1;
      set_active(j);
    } else if (nj.tree != ni.tree) {
      bridge = source ? a : arcs_[a].reverse;  // always from the source tree to the sink tree
      return true;
    } else if (nj.stamp <= ni.stamp && nj.distance > ni.distance) {
      // A shorter way to the terminal through i: re-hang j (keeps the trees shallow).
      nj.parent = arcs_[a].reverse;
      nj.stamp = ni.stamp;
      nj.distance = ni.distance + 1;
    }
  }
  return false;
}

void MaxFlow::augment(Arc bridge) {
  // Bottleneck: the bridge, the source-side path (arcs parent -> child), the sink-side path
  // (arcs child -> parent) and the two terminal capacities.
  double f = arcs_[bridge].residual;
  Node i = arcs_[arcs_[bridge].reverse].head;
  for (Arc p; (p = nodes_[i].parent) != kTerminal; i = arcs_[p].head) f = std::min(f, arcs_[arcs_[p].reverse].residual);
  f = std::min(f, nodes_[i].terminal);
  i = arcs_[bridge].head;
  for (Arc p; (p = nodes_[i].parent) != kTerminal; i = arcs_[p].head) f = std::min(f, arcs_[p].residual);
  f = std::min(f, -nodes_[i].terminal);

  arcs_[bridge].residual -= f;
  arcs_[arcs_[bridge].reverse].residual += f;
  i = arcs_[arcs_[bridge].reverse].head;
  for (Arc p; (p = nodes_[i].parent) != kTerminal;) {
    arcs_[p].residual += f;
    arcs_[arcs_[p].reverse].residual -= f;
    const Node up = arcs_[p].head;
    if (!(arcs_[arcs_[p].reverse].residual > zero_)) {
      nodes_[i].parent = kOrphan;
      orphans_.push_back(i);
    }
    i = up;
  }
  nodes_[i].terminal -= f;
  if (!(nodes_[i].terminal > zero_)) {
    nodes_[i].parent = kOrphan;
    orphans_.push_back(i);
  }
  i = arcs_[bridge].head;
  for (Arc p; (p = nodes_[i].parent) != kTerminal;) {
    arcs_[arcs_[p].reverse].residual += f;
    arcs_[p].residual -= f;
    const Node up = arcs_[p].head;
    if (!(arcs_[p].residual > zero_)) {
      nodes_[i].parent = kOrphan;
      orphans_.push_back(i);
    }
    i = up;
  }
  nodes_[i].terminal += f;
  if (!(nodes_[i].terminal < -zero_)) {
    nodes_[i].parent = kOrphan;
    orphans_.push_back(i);
  }
  flow_ += f;
  ++augmentations_;
}

void MaxFlow::push_two_arc_paths() {
  // Most paths in a labelling graph are source -> i -> j -> sink: pushing them in one pass
  // over the arcs is far cheaper than finding each with the search trees.
  for (Node i = 0; i < nodes_.size(); ++i) {
    NodeData& ni = nodes_[i];
    for (Arc a = ni.first, end = arcs_end(i); a < end && ni.terminal > zero_; ++a) {
      NodeData& nj = nodes_[arcs_[a].head];
      if (!(nj.terminal < -zero_) || !(arcs_[a].residual > zero_)) continue;
      const double f = std::min({ni.terminal, -nj.terminal, arcs_[a].residual});
      ni.terminal -= f;
      nj.terminal += f;
      arcs_[a].residual -= f;
      arcs_[arcs_[a].reverse].residual += f;
      flow_ += f;
    }
  }
}

bool MaxFlow::rooted(Node j, std::uint32_t& distance) {
  // Walk up to the terminal (or to a node already checked in this round, whose distance is
  // known); an orphan on the way means j is cut off.
  std::uint32_t d = 0;
  for (Node k = j;;) {
    NodeData& n = nodes_[k];
    if (n.stamp == time_) {
      d += n.distance;
      break;
    }
    const Arc p = n.parent;
    ++d;
    if (p == kTerminal) {
      n.stamp = time_;
      n.distance = 1;
      break;
    }
    if (p == kOrphan || p == kNone) return false;
    k = arcs_[p].head;
  }
  // Record the distances along the path for the next queries of this round.
  distance = d;
  for (Node k = j; nodes_[k].stamp != time_; k = arcs_[nodes_[k].parent].head) {
    nodes_[k].stamp = time_;
    nodes_[k].distance = d--;
  }
  return true;
}

void MaxFlow::adopt(Node i) {
  NodeData& ni = nodes_[i];
  const bool source = ni.tree == Tree::source;
  Arc best = kNone;
  std::uint32_t best_distance = std::numeric_limits<std::uint32_t>::max();
  const Arc end = arcs_end(i);
  for (Arc a = ni.first; a < end; ++a) {
    // A parent j must send (source tree: j -> i) or take (sink tree: i -> j) flow.
    if (!((source ? arcs_[arcs_[a].reverse].residual : arcs_[a].residual) > zero_)) continue;
    const Node j = arcs_[a].head;
    if (nodes_[j].tree != ni.tree) continue;
    std::uint32_t d = 0;
    if (rooted(j, d) && d < best_distance) {
      best = a;
      best_distance = d;
    }
  }
  if (best != kNone) {
    ni.parent = best;
    ni.stamp = time_;
    ni.distance = best_distance + 1;
    return;
  }
  // No parent: i leaves its tree. Its children become orphans; neighbours that could grow
  // into it again are made active.
  for (Arc a = ni.first; a < end; ++a) {
    const Node j = arcs_[a].head;
    NodeData& nj = nodes_[j];
    if (nj.tree != ni.tree) continue;
    if ((source ? arcs_[arcs_[a].reverse].residual : arcs_[a].residual) > zero_) set_active(j);
    if (nj.parent != kTerminal && nj.parent != kOrphan && nj.parent != kNone && arcs_[nj.parent].head == i) {
      nj.parent = kOrphan;
      orphans_.push_back(j);
    }
  }
  ni.tree = Tree::free;
  ni.parent = kNone;
}

double MaxFlow::solve() {
  // Sums of pushes leave rounding crumbs on arcs that are saturated in exact arithmetic:
  // residuals this far below the largest capacity count as zero, or the cut would leak.
  if (solved_) throw ProcessingError("max-flow: solve() called twice");
  solved_ = true;
  zero_ = largest_ * kRelativeZero;
  lay_out_arcs();
  push_two_arc_paths();
  for (Node i = 0; i < nodes_.size(); ++i) {
    NodeData& n = nodes_[i];
    if (!(std::abs(n.terminal) > zero_)) continue;
    n.tree = n.terminal > 0 ? Tree::source : Tree::sink;
    n.parent = kTerminal;
    n.stamp = 0;
    n.distance = 1;
    set_active(i);
  }
  constexpr Node kNoNode = std::numeric_limits<Node>::max();
  Node current = kNoNode;  // a node that found a path is grown again first: its tree is warm
  for (;;) {
    Node i = current != kNoNode && nodes_[current].tree != Tree::free ? current : next_active();
    current = kNoNode;
    if (i == kNoNode) break;
    Arc bridge = kNone;
    if (!grow(i, bridge)) continue;
    current = i;
    ++time_;
    augment(bridge);
    // First in, first out: the path's orphans look for parents before the children they cut
    // off in turn (3-6 % less time than last in, first out on the bench's graphs).
    for (std::size_t k = 0; k < orphans_.size(); ++k) adopt(orphans_[k]);
    orphans_.clear();
  }
  return flow_;
}

std::vector<std::uint8_t> MaxFlow::source_side() const {
  // When solve() stops no node is active, so the source tree cannot grow: every residual arc
  // out of it stays inside, and each of its nodes hangs from the source by residual arcs.
  // It is exactly the set reachable from the source.
  std::vector<std::uint8_t> side(nodes_.size(), 0);
  for (Node i = 0; i < nodes_.size(); ++i) side[i] = nodes_[i].tree == Tree::source ? 1 : 0;
  return side;
}

}  // namespace citymesh
