// SPDX-License-Identifier: MIT
#include "citymesh/mosaic/binary_energy.h"

#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <numeric>
#include <random>

#include "citymesh/core/error.h"
#include "citymesh/mosaic/max_flow.h"

namespace citymesh {

void PairList::too_many_terms() { throw ProcessingError("energy: too many pair terms"); }

std::uint32_t PairList::row(std::size_t k) const {
  // The ends first, without bisection: every begin() and end() asks for them.
  if (k == 0 || row_starts_.empty()) return 0;
  if (k >= ends_.size()) return static_cast<std::uint32_t>(row_starts_.size() - 1);
  const auto after = std::upper_bound(row_starts_.begin(), row_starts_.end(), k,
                                      [](std::size_t term, std::uint32_t start) { return term < start; });
  return after == row_starts_.begin() ? 0 : static_cast<std::uint32_t>(after - row_starts_.begin() - 1);
}

double BinaryEnergy::evaluate(std::span<const std::int8_t> x) const {
  double e = 0;
  for (std::size_t i = 0; i < unary.size(); ++i) e += unary[i][static_cast<std::size_t>(x[i])];
  for (const Pair& p : pairs) e += p.value(x[p.i] != 0, x[p.j] != 0);
  return e;
}

std::array<double, 2> BinaryEnergy::evaluate(std::span<const std::int8_t> x, std::span<const std::int8_t> y) const {
  double ex = 0, ey = 0;
  for (std::size_t i = 0; i < unary.size(); ++i) {
    ex += unary[i][static_cast<std::size_t>(x[i])];
    ey += unary[i][static_cast<std::size_t>(y[i])];
  }
  for (const Pair& p : pairs) {
    ex += p.value(x[p.i] != 0, x[p.j] != 0);
    ey += p.value(y[p.i] != 0, y[p.j] != 0);
  }
  return {ex, ey};
}

namespace {

/// The interaction strength of a pair: e01 + e10 - e00 - e11, > 0 for submodular terms.
double coupling(const BinaryEnergy::Pair& p) { return p.e01 + p.e10 - p.e00 - p.e11; }

/// The pair with its ends flipped as asked (x -> 1 - x).
BinaryEnergy::Pair flip_pair(BinaryEnergy::Pair p, bool flip_i, bool flip_j) {
  if (flip_i) {
    std::swap(p.e00, p.e10);
    std::swap(p.e01, p.e11);
  }
  if (flip_j) {
    std::swap(p.e00, p.e01);
    std::swap(p.e10, p.e11);
  }
  // Rounding can leave a modular term a hair non-submodular: it carries no coupling.
  if (!p.submodular() && coupling(p) > -1e-12 * (std::abs(p.e00) + std::abs(p.e11) + 1)) p.e11 = p.e01 + p.e10 - p.e00;
  return p;
}

/// The terms of the s-t graph of cut_graph(), handed out as they are made: add_edge(from, to,
/// capacity, reverse capacity) in the order of the energy's pairs, then add_terminal(node,
/// from the source, to the sink) for every node with one, in node order.
template <class AddEdge, class AddTerminal>
void make_cut(const BinaryEnergy& e, bool doubled, std::span<const std::uint8_t> flips, AddEdge add_edge,
              AddTerminal add_terminal) {
  const auto flipped_at = [&flips](std::uint32_t i) { return !flips.empty() && flips[i] != 0; };
  const std::size_t n = e.size();
  std::vector<double> cost_of_one(n, 0.0);  // unary cost of x_i = 1 over x_i = 0 (constants dropped)
  for (std::size_t i = 0; i < n; ++i) {
    const auto v = static_cast<std::uint32_t>(i);
    cost_of_one[i] = flipped_at(v) ? e.unary[i][0] - e.unary[i][1] : e.unary[i][1] - e.unary[i][0];
  }
  const auto bar = [n](std::uint32_t i) { return static_cast<std::uint32_t>(n + i); };
  for (const BinaryEnergy::Pair& term : e.pairs) {
    const BinaryEnergy::Pair p = flips.empty() ? term : flip_pair(term, flipped_at(term.i), flipped_at(term.j));
    // Each term is written as unary parts plus two "both ways" costs of weights alpha and
    // beta (alpha + beta = |coupling|), split so that the unary parts are balanced: unary
    // parts push flow through the graph from terminal to terminal, and a split that leaves
    // the overlap terms none spares millions of augmentations.
    const double c = coupling(p);
    const std::uint32_t i = p.i, j = p.j;
    if (c >= 0) {
      // e00 + u_i x_i + u_j x_j + alpha [x_i=0, x_j=1] + beta [x_i=1, x_j=0].
      const double beta = std::clamp((2 * p.e10 - p.e00 - p.e11) / 2, 0.0, c), alpha = c - beta;
      cost_of_one[p.i] += p.e10 - p.e00 - beta;
      cost_of_one[p.j] += p.e01 - p.e00 - alpha;
      // alpha: cut when i is on the source side and j is not; beta: the other way round.
      if (alpha > 0 || beta > 0) {
        add_edge(i, j, alpha, beta);
        if (doubled) add_edge(bar(j), bar(i), alpha, beta);
      }
    } else {
      if (!doubled) throw ProcessingError("graph cut: a non-submodular term in a single cut");
      // k + u_i x_i + u_j x_j + alpha [x_i=0, x_j=0] + beta [x_i=1, x_j=1].
      const double beta = std::clamp((2 * p.e11 - p.e01 - p.e10) / 2, 0.0, -c), alpha = -c - beta;
      cost_of_one[p.i] += p.e11 - p.e01 - beta;
      cost_of_one[p.j] += p.e11 - p.e10 - beta;
      if (alpha > 0) {
        add_edge(i, bar(j), alpha, 0.0);  // x_i = 0 (i source side), x_j = 0 (bar j sink side)
        add_edge(j, bar(i), alpha, 0.0);
      }
      if (beta > 0) {
        add_edge(bar(i), j, beta, 0.0);  // x_i = 1 (bar i source side), x_j = 1 (j sink side)
        add_edge(bar(j), i, beta, 0.0);
      }
    }
  }
  // x_i = 1 puts node i on the sink side, cutting source -> i: a positive cost goes there.
  for (std::size_t i = 0; i < n; ++i) {
    const double d = cost_of_one[i];
    if (d != 0) add_terminal(static_cast<std::uint32_t>(i), d > 0 ? d : 0.0, d < 0 ? -d : 0.0);
  }
  if (!doubled) return;
  for (std::size_t i = 0; i < n; ++i) {
    const double d = cost_of_one[i];
    if (d != 0) add_terminal(bar(static_cast<std::uint32_t>(i)), d < 0 ? -d : 0.0, d > 0 ? d : 0.0);
  }
}

/// The graph of cut_graph() loaded straight into our max-flow.
MaxFlow max_flow_of(const BinaryEnergy& e, bool doubled, std::span<const std::uint8_t> flips = {}) {
  MaxFlow g(doubled ? 2 * e.size() : e.size());
  g.reserve_edges(doubled ? 2 * e.pairs.size() : e.pairs.size());
  make_cut(
      e, doubled, flips,
      [&g](std::uint32_t from, std::uint32_t to, double capacity, double reverse) {
        g.add_edge(from, to, capacity, reverse);
      },
      [&g](std::uint32_t node, double from_source, double to_sink) { g.add_terminal(node, from_source, to_sink); });
  return g;
}

}  // namespace

CutGraph cut_graph(const BinaryEnergy& e, bool doubled, std::span<const std::uint8_t> flips) {
  CutGraph g;
  g.nodes = doubled ? 2 * e.size() : e.size();
  g.terminal.assign(g.nodes, {0.0, 0.0});
  g.arcs.reserve(doubled ? 2 * e.pairs.size() : e.pairs.size());
  make_cut(
      e, doubled, flips,
      [&g](std::uint32_t from, std::uint32_t to, double capacity, double reverse) {
        g.arcs.push_back({from, to, capacity, reverse});
      },
      [&g](std::uint32_t node, double from_source, double to_sink) {
        g.terminal[node] = {from_source, to_sink};
      });
  return g;
}

bool flips_make_submodular(const BinaryEnergy& e, std::span<const std::uint8_t> flips) {
  return std::all_of(e.pairs.begin(), e.pairs.end(), [&](const BinaryEnergy::Pair& p) {
    const double c = coupling(p);
    return c == 0 || (c < 0) == ((flips[p.i] != 0) != (flips[p.j] != 0));
  });
}

namespace {

/// Variables joined by coupled pairs, each with its parity (flipped or not) against its set's
/// root: union-find with path compression.
class ParitySets {
 public:
  explicit ParitySets(std::size_t n) : parent_(n), parity_(n, 0) {
    std::iota(parent_.begin(), parent_.end(), std::uint32_t{0});
  }

  /// Joins i and j with parity `differ` between them; false when they are joined already with
  /// the other parity (an odd cycle of differing pairs).
  bool join(std::uint32_t i, std::uint32_t j, bool differ) {
    const auto [ri, pi] = find(i);
    const auto [rj, pj] = find(j);
    if (ri == rj) return (pi ^ pj) == std::uint8_t{differ};
    parent_[ri] = rj;
    parity_[ri] = static_cast<std::uint8_t>(pi ^ pj ^ std::uint8_t{differ});
    return true;
  }

  /// v's root and v's parity against it; points the path at the root.
  std::pair<std::uint32_t, std::uint8_t> find(std::uint32_t v) {
    std::uint32_t root = v;
    std::uint8_t parity = 0;
    while (parent_[root] != root) {
      parity ^= parity_[root];
      root = parent_[root];
    }
    for (std::uint32_t u = v, pu = parity; parent_[u] != u;) {
      const std::uint32_t next = parent_[u];
      const auto p_next = static_cast<std::uint8_t>(pu ^ parity_[u]);
      parent_[u] = root;
      parity_[u] = static_cast<std::uint8_t>(pu);
      u = next;
      pu = p_next;
    }
    return {root, parity};
  }

 private:
  std::vector<std::uint32_t> parent_;
  std::vector<std::uint8_t> parity_;
};

}  // namespace

std::optional<std::vector<std::uint8_t>> submodular_flips(const BinaryEnergy& e) {
  // Pair by pair, stopping at the first cycle with an odd number of differing pairs: with
  // three meshes or more one comes early (a breadth-first colouring first built the adjacency
  // of every term, a tenth of the mosaic's solve on the bench street). Last pair first: the
  // mosaic lists its seam terms (which never differ) before its overlap terms, and these by
  // triangle, so three meshes overlapping close a cycle within the last meshes' overlaps.
  const std::size_t n = e.size();
  ParitySets sets(n);
  for (auto it = e.pairs.end(); it != e.pairs.begin();) {
    const BinaryEnergy::Pair p = *--it;
    const double c = coupling(p);
    if (c != 0 && !sets.join(p.i, p.j, c < 0)) return std::nullopt;
  }
  // The colouring that leaves the lowest variable of each connected set unflipped: every
  // variable's parity against the root, less that lowest variable's.
  std::vector<std::uint8_t> flips(n);
  std::vector<std::int8_t> base(n, -1);  // per root: its lowest variable's parity
  for (std::uint32_t v = 0; v < n; ++v) {
    const auto [root, parity] = sets.find(v);
    if (base[root] < 0) base[root] = static_cast<std::int8_t>(parity);
    flips[v] = static_cast<std::uint8_t>(parity ^ base[root]);
  }
  return flips;
}

std::vector<std::int8_t> minimise_by_flipped_cut(const BinaryEnergy& e, std::span<const std::uint8_t> flips) {
  MaxFlow g = max_flow_of(e, /*doubled=*/false, flips);
  g.solve();
  const std::vector<std::uint8_t> source = g.source_side();
  std::vector<std::int8_t> x(e.size());
  for (std::size_t i = 0; i < x.size(); ++i) x[i] = static_cast<std::int8_t>((source[i] != 0 ? 0 : 1) ^ flips[i]);
  return x;
}

std::vector<std::int8_t> qpbo(const BinaryEnergy& e) {
  const std::size_t n = e.size();
  MaxFlow g = max_flow_of(e, /*doubled=*/true);
  g.solve();
  // Nodes reachable from the source lie on the source side of every minimum cut: x_i = 0 when
  // i is, x_i = 1 when its negation is; both never happen (that would be an s-t path).
  const std::vector<std::uint8_t> source = g.source_side();
  std::vector<std::int8_t> x(n, kUnlabelled);
  for (std::size_t i = 0; i < n; ++i) {
    if (source[i] != 0) x[i] = 0;
    if (source[n + i] != 0) x[i] = 1;
  }
  return x;
}

}  // namespace citymesh
