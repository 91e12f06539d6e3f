// SPDX-License-Identifier: MIT
// Boost.Graph's boykov_kolmogorov_max_flow on a citymesh cut graph: the reference our
// max-flow is measured against (benchmark only; Boost is not a dependency of citymesh).
#pragma once

#include <boost/graph/adjacency_list.hpp>
#include <boost/graph/boykov_kolmogorov_max_flow.hpp>

#include "citymesh/core/stopwatch.h"
#include "citymesh/mosaic/binary_energy.h"

namespace citymesh::bench {

struct BoostRun {
  double flow = 0, seconds_build = 0, seconds_solve = 0;
};

inline BoostRun boost_max_flow(const CutGraph& c) {
  using Traits = boost::adjacency_list_traits<boost::vecS, boost::vecS, boost::directedS>;
  using Graph = boost::adjacency_list<
      boost::vecS, boost::vecS, boost::directedS,
      boost::property<boost::vertex_index_t, long,
                      boost::property<boost::vertex_color_t, boost::default_color_type,
                                      boost::property<boost::vertex_distance_t, long,
                                                      boost::property<boost::vertex_predecessor_t, Traits::edge_descriptor>>>>,
      boost::property<boost::edge_capacity_t, double,
                      boost::property<boost::edge_residual_capacity_t, double,
                                      boost::property<boost::edge_reverse_t, Traits::edge_descriptor>>>>;
  Stopwatch clock;
  Graph g(c.nodes + 2);
  const auto source = static_cast<Traits::vertex_descriptor>(c.nodes), sink = source + 1;
  auto capacity = boost::get(boost::edge_capacity, g);
  auto reverse = boost::get(boost::edge_reverse, g);
  const auto add = [&](std::size_t from, std::size_t to, double cap, double reverse_cap = 0) {
    const auto e = boost::add_edge(from, to, g).first, r = boost::add_edge(to, from, g).first;
    capacity[e] = cap;
    capacity[r] = reverse_cap;
    reverse[e] = r;
    reverse[r] = e;
  };
  for (std::size_t i = 0; i < c.nodes; ++i) {
    if (c.terminal[i][0] > 0) add(source, i, c.terminal[i][0]);
    if (c.terminal[i][1] > 0) add(i, sink, c.terminal[i][1]);
  }
  for (const CutGraph::Arc& a : c.arcs) add(a.from, a.to, a.capacity, a.reverse_capacity);
  BoostRun run;
  run.seconds_build = clock.restart();
  run.flow = boost::boykov_kolmogorov_max_flow(g, source, sink);
  run.seconds_solve = clock.seconds();
  return run;
}

}  // namespace citymesh::bench
