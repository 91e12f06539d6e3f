// SPDX-License-Identifier: MIT
#include "citymesh/mosaic/max_flow.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <deque>
#include <random>
#include <vector>

namespace citymesh {
namespace {

struct ReferenceFlow {
  double flow = 0;
  std::vector<bool> reachable;  ///< per node: reachable from the source in the final residual graph
};

/// Edmonds-Karp on a dense capacity matrix: node 0 the source, node n + 1 the sink.
ReferenceFlow reference_max_flow(std::vector<std::vector<double>> cap) {
  const std::size_t n = cap.size(), s = 0, t = n - 1;
  double flow = 0;
  for (;;) {
    std::vector<int> parent(n, -1);
    parent[s] = static_cast<int>(s);
    std::deque<std::size_t> queue{s};
    while (!queue.empty() && parent[t] < 0) {
      const std::size_t u = queue.front();
      queue.pop_front();
      for (std::size_t v = 0; v < n; ++v) {
        if (parent[v] < 0 && cap[u][v] > 1e-12) {
          parent[v] = static_cast<int>(u);
          queue.push_back(v);
        }
      }
    }
    if (parent[t] < 0) {
      ReferenceFlow out{flow, std::vector<bool>(n)};
      for (std::size_t v = 0; v < n; ++v) out.reachable[v] = parent[v] >= 0;
      return out;
    }
    double f = 1e300;
    for (std::size_t v = t; v != s; v = static_cast<std::size_t>(parent[v])) {
      f = std::min(f, cap[static_cast<std::size_t>(parent[v])][v]);
    }
    for (std::size_t v = t; v != s; v = static_cast<std::size_t>(parent[v])) {
      const auto u = static_cast<std::size_t>(parent[v]);
      cap[u][v] -= f;
      cap[v][u] += f;
    }
    flow += f;
  }
}

/// A graph given both to MaxFlow and as a dense matrix for the reference (node 0 the source,
/// node n + 1 the sink).
struct TwinGraph {
  explicit TwinGraph(int nodes)
      : n(nodes),
        dense(static_cast<std::size_t>(nodes + 2), std::vector<double>(nodes + 2, 0.0)),
        g(static_cast<std::size_t>(nodes)) {}
  void terminal(int i, double a, double b) {
    g.add_terminal(static_cast<MaxFlow::Node>(i), a, b);
    dense[0][static_cast<std::size_t>(i + 1)] += a;
    dense[static_cast<std::size_t>(i + 1)][static_cast<std::size_t>(n + 1)] += b;
  }
  void edge(int i, int j, double c, double r) {
    g.add_edge(static_cast<MaxFlow::Node>(i), static_cast<MaxFlow::Node>(j), c, r);
    dense[static_cast<std::size_t>(i + 1)][static_cast<std::size_t>(j + 1)] += c;
    dense[static_cast<std::size_t>(j + 1)][static_cast<std::size_t>(i + 1)] += r;
  }
  int n;
  std::vector<std::vector<double>> dense;
  MaxFlow g;
};

/// Solves and checks the flow, and that the source side is the smallest minimum
/// cut: what the source reaches in the residual graph, the same set for every maximum flow.
void expect_reference_flow_and_cut(TwinGraph& t, int trial) {
  const int n = t.n;
  const double flow = t.g.solve();
  const ReferenceFlow reference = reference_max_flow(t.dense);
  const double expected = reference.flow;
  ASSERT_NEAR(flow, expected, 1e-9 * (1 + expected)) << "trial " << trial;
  const std::vector<std::uint8_t> side = t.g.source_side();
  for (int i = 0; i < n; ++i) {
    ASSERT_EQ(side[static_cast<std::size_t>(i)] != 0, reference.reachable[static_cast<std::size_t>(i + 1)])
        << "trial " << trial << ", node " << i;
  }
  double cut = 0;
  for (std::size_t a = 0; a < t.dense.size(); ++a) {
    for (std::size_t b = 0; b < t.dense.size(); ++b) {
      const bool a_source = a == 0 || (a <= static_cast<std::size_t>(n) && side[a - 1] != 0);
      const bool b_source = b == 0 || (b <= static_cast<std::size_t>(n) && side[b - 1] != 0);
      if (a_source && !b_source) cut += t.dense[a][b];
    }
  }
  ASSERT_NEAR(cut, expected, 1e-9 * (1 + expected)) << "trial " << trial;
}

TEST(MaxFlow, EqualsEdmondsKarpAndItsCutOnRandomGraphs) {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 300; ++trial) {
    const int n = 2 + static_cast<int>(rng() % 40);
    const bool integral = trial % 2 == 0;
    std::uniform_real_distribution<double> u(0, 10);
    const auto capacity = [&] { return integral ? std::floor(u(rng)) : u(rng); };
    TwinGraph t(n);
    for (int i = 0; i < n; ++i) {
      if (rng() % 3 == 0) {
        const double a = capacity(), b = capacity();
        t.terminal(i, a, b);
      }
    }
    const int edges = static_cast<int>(rng() % static_cast<unsigned>(4 * n + 1));
    for (int k = 0; k < edges; ++k) {
      const int i = static_cast<int>(rng() % static_cast<unsigned>(n)),
                j = static_cast<int>(rng() % static_cast<unsigned>(n));
      if (i == j) continue;
      const double c = capacity(), r = rng() % 2 == 0 ? 0.0 : capacity();
      t.edge(i, j, c, r);
    }
    expect_reference_flow_and_cut(t, trial);
  }
}

TEST(MaxFlow, EqualsEdmondsKarpAndItsCutOnLabellingGrids) {
  // Grids like a labelling's: a few terminals far apart, so paths are long and saturating one
  // leaves deep subtrees to re-adopt (what a random graph of 40 nodes rarely exercises).
  std::mt19937 rng(5);
  for (int trial = 0; trial < 60; ++trial) {
    const int w = 4 + static_cast<int>(rng() % 13), h = 2 + static_cast<int>(rng() % 10);
    std::uniform_real_distribution<double> u(0, 4);
    TwinGraph t(w * h);
    for (int i = 0; i < w * h; ++i) {
      if (rng() % 5 == 0) t.terminal(i, rng() % 2 == 0 ? u(rng) : 0.0, rng() % 2 == 0 ? u(rng) : 0.0);
      if (i % w + 1 < w) t.edge(i, i + 1, u(rng), u(rng));
      if (i + w < w * h) t.edge(i, i + w, u(rng), rng() % 3 == 0 ? 0.0 : u(rng));
      const int far = static_cast<int>(rng() % static_cast<unsigned>(w * h));  // a long-range pair now and then
      if (rng() % 8 == 0 && far != i) t.edge(i, far, u(rng), u(rng));
    }
    expect_reference_flow_and_cut(t, trial);
  }
}

/// s -> 0 (5), 0 -> 1 (3), 1 -> t (4), plus 0 -> t (1): max flow 4.
MaxFlow chain_and_parallel_paths() {
  MaxFlow g(2);
  g.add_terminal(0, 5, 1);
  g.add_edge(0, 1, 3, 0);
  g.add_terminal(1, 0, 4);
  return g;
}

TEST(MaxFlow, ChainAndParallelPaths) {
  MaxFlow g = chain_and_parallel_paths();
  EXPECT_DOUBLE_EQ(g.solve(), 4.0);
  const auto side = g.source_side();
  EXPECT_EQ(side[0], 1);
  EXPECT_EQ(side[1], 0);
}

TEST(MaxFlow, RefusesSelfLoops) {
  MaxFlow g(1);
  EXPECT_ANY_THROW(g.add_edge(0, 0, 1, 1));
}

TEST(MaxFlow, RefusesASecondSolveAndEdgesAfterIt) {
  // solve() lays the arcs out once: a second call or a later edge would be silently lost.
  MaxFlow g = chain_and_parallel_paths();
  EXPECT_DOUBLE_EQ(g.solve(), 4.0);
  EXPECT_ANY_THROW(g.solve());
  EXPECT_ANY_THROW(g.add_edge(1, 0, 1, 0));
}

}  // namespace
}  // namespace citymesh
