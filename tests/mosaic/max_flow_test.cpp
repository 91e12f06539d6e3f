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

TEST(MaxFlow, EqualsEdmondsKarpAndItsCutOnRandomGraphs) {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 300; ++trial) {
    const int n = 2 + static_cast<int>(rng() % 40);
    const bool integral = trial % 2 == 0;
    std::uniform_real_distribution<double> u(0, 10);
    const auto capacity = [&] { return integral ? std::floor(u(rng)) : u(rng); };
    std::vector<std::vector<double>> dense(static_cast<std::size_t>(n + 2), std::vector<double>(n + 2, 0.0));
    MaxFlow g(static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i) {
      if (rng() % 3 == 0) {
        const double a = capacity(), b = capacity();
        g.add_terminal(static_cast<MaxFlow::Node>(i), a, b);
        dense[0][static_cast<std::size_t>(i + 1)] += a;
        dense[static_cast<std::size_t>(i + 1)][static_cast<std::size_t>(n + 1)] += b;
      }
    }
    const int edges = static_cast<int>(rng() % static_cast<unsigned>(4 * n + 1));
    for (int k = 0; k < edges; ++k) {
      const int i = static_cast<int>(rng() % static_cast<unsigned>(n)), j = static_cast<int>(rng() % static_cast<unsigned>(n));
      if (i == j) continue;
      const double c = capacity(), r = rng() % 2 == 0 ? 0.0 : capacity();
      g.add_edge(static_cast<MaxFlow::Node>(i), static_cast<MaxFlow::Node>(j), c, r);
      dense[static_cast<std::size_t>(i + 1)][static_cast<std::size_t>(j + 1)] += c;
      dense[static_cast<std::size_t>(j + 1)][static_cast<std::size_t>(i + 1)] += r;
    }
    const double flow = g.solve();
    const ReferenceFlow reference = reference_max_flow(dense);
    const double expected = reference.flow;
    ASSERT_NEAR(flow, expected, 1e-9 * (1 + expected)) << "trial " << trial;
    // The source side is a cut of exactly that capacity, and the smallest one: what the source
    // reaches in the residual graph, the same set for every maximum flow.
    const std::vector<std::uint8_t> side = g.source_side();
    for (int i = 0; i < n; ++i) {
      ASSERT_EQ(side[static_cast<std::size_t>(i)] != 0, reference.reachable[static_cast<std::size_t>(i + 1)])
          << "trial " << trial << ", node " << i;
    }
    double cut = 0;
    for (std::size_t a = 0; a < dense.size(); ++a) {
      for (std::size_t b = 0; b < dense.size(); ++b) {
        const bool a_source = a == 0 || (a <= static_cast<std::size_t>(n) && side[a - 1] != 0);
        const bool b_source = b == 0 || (b <= static_cast<std::size_t>(n) && side[b - 1] != 0);
        if (a_source && !b_source) cut += dense[a][b];
      }
    }
    ASSERT_NEAR(cut, expected, 1e-9 * (1 + expected)) << "trial " << trial;
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
