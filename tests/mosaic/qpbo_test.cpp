// SPDX-License-Identifier: MIT
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <random>
#include <ranges>
#include <span>
#include <tuple>
#include <utility>
#include <vector>

#include "citymesh/core/parallel.h"
#include "citymesh/mosaic/binary_energy.h"
#include "restricted_energy.h"

namespace citymesh {
namespace {

struct Enumeration {
  double minimum = 0;
  std::vector<std::vector<std::int8_t>> optima;  ///< every labelling within 1e-9 of the minimum
};

Enumeration enumerate(const BinaryEnergy& e) {
  const std::size_t n = e.size();
  Enumeration out;
  out.minimum = 1e300;
  std::vector<double> values(std::size_t{1} << n);
  std::vector<std::int8_t> x(n);
  for (std::size_t m = 0; m < values.size(); ++m) {
    for (std::size_t i = 0; i < n; ++i) x[i] = static_cast<std::int8_t>((m >> i) & 1);
    values[m] = e.evaluate(x);
    out.minimum = std::min(out.minimum, values[m]);
  }
  for (std::size_t m = 0; m < values.size(); ++m) {
    if (values[m] > out.minimum + 1e-9) continue;
    for (std::size_t i = 0; i < n; ++i) x[i] = static_cast<std::int8_t>((m >> i) & 1);
    out.optima.push_back(x);
  }
  return out;
}

/// A random energy; with `bipartite`, variables are split in two "meshes": pairs across them
/// are overlap-like (non-submodular: x_i x_j costs), pairs inside one are seam-like (XOR costs).
BinaryEnergy random_energy(std::mt19937& rng, std::size_t n, bool bipartite) {
  std::uniform_real_distribution<double> u(-2, 2), w(0, 3);
  BinaryEnergy e;
  e.unary.resize(n);
  for (auto& t : e.unary) t = {u(rng), u(rng)};
  const std::size_t pairs = n + rng() % (2 * n);
  for (std::size_t k = 0; k < pairs; ++k) {
    auto i = static_cast<std::uint32_t>(rng() % n), j = static_cast<std::uint32_t>(rng() % n);
    if (i == j) continue;
    if (!bipartite) {
      e.pairs.push_back({i, j, u(rng), u(rng), u(rng), u(rng)});
    } else if ((i < n / 2) != (j < n / 2)) {
      e.pairs.push_back({i, j, 0, 0, 0, w(rng)});  // overlap: both kept costs
    } else {
      const double c = w(rng);
      e.pairs.push_back({i, j, 0, c, c, 0});  // seam: differing labels cost
    }
  }
  return e;
}

bool agrees_with_every_optimum(const std::vector<std::int8_t>& partial, const Enumeration& all) {
  for (const auto& opt : all.optima) {
    for (std::size_t i = 0; i < partial.size(); ++i) {
      if (partial[i] != kUnlabelled && partial[i] != opt[i]) return false;
    }
  }
  return true;
}

TEST(Qpbo, LabelledVariablesTakeTheirLabelInEveryGlobalMinimum) {
  // Several terms on one pair, sums of pushes that saturate an arc only up to rounding: the
  // cases that once leaked a wrong label through a 1e-16 residual.
  std::mt19937 rng(21);
  std::size_t labelled = 0, total = 0, nonsubmodular = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    const std::size_t n = 1 + rng() % (trial < 2000 ? 4 : 12);
    const BinaryEnergy e = random_energy(rng, n, false);
    for (const auto& p : e.pairs) nonsubmodular += p.submodular() ? 0 : 1;
    const std::vector<std::int8_t> partial = qpbo(e);
    ASSERT_TRUE(agrees_with_every_optimum(partial, enumerate(e))) << "trial " << trial;
    labelled += static_cast<std::size_t>(std::count_if(partial.begin(), partial.end(), [](auto v) { return v >= 0; }));
    total += n;
  }
  EXPECT_GT(nonsubmodular, 500u);
  // Roof duality labels a good share of such small random problems, not all of them.
  EXPECT_GT(labelled, total / 10);
  EXPECT_LT(labelled, total);
}

TEST(Qpbo, ImprovementNeverRaisesTheEnergyAndOftenFindsTheMinimum) {
  std::mt19937 rng(22);
  int optimal = 0, trials = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const std::size_t n = 2 + rng() % 11;
    const BinaryEnergy e = random_energy(rng, n, false);
    const std::vector<std::int8_t> partial = qpbo(e);
    double completed = 0;
    const std::vector<std::int8_t> x = improve_qpbo_i(e, partial, {}, &completed);
    ASSERT_EQ(x.size(), n);
    for (std::size_t i = 0; i < n; ++i) {
      ASSERT_TRUE(x[i] == 0 || x[i] == 1);
      if (partial[i] != kUnlabelled) {
        ASSERT_EQ(x[i], partial[i]);  // persistent labels stay
      }
    }
    const double energy = e.evaluate(x);
    if (std::count(partial.begin(), partial.end(), kUnlabelled) > 0) {
      ASSERT_LE(energy, completed + 1e-12);
    }
    const Enumeration all = enumerate(e);
    ASSERT_GE(energy, all.minimum - 1e-9);
    optimal += energy <= all.minimum + 1e-9 ? 1 : 0;
    ++trials;
  }
  EXPECT_GT(optimal, trials * 8 / 10) << optimal << " of " << trials;
}

TEST(Qpbo, TwoMeshEnergiesAreFlippedAndSolvedExactly) {
  std::mt19937 rng(23);
  for (int trial = 0; trial < 300; ++trial) {
    const std::size_t n = 2 + rng() % 11;
    const BinaryEnergy e = random_energy(rng, n, true);
    const auto flips = submodular_flips(e);
    ASSERT_TRUE(flips.has_value()) << "trial " << trial;
    const std::vector<std::int8_t> x = minimise_by_flipped_cut(e, *flips);
    ASSERT_NEAR(e.evaluate(x), enumerate(e).minimum, 1e-9) << "trial " << trial;
    MinimiseStats stats;
    const std::vector<std::int8_t> y = minimise(e, {}, stats);
    EXPECT_TRUE(stats.exact);
    EXPECT_NEAR(stats.energy, e.evaluate(y), 1e-12);
  }
}

GroupMoveParams sweeps(int max_sweeps) {
  GroupMoveParams params;
  params.max_sweeps = max_sweeps;
  return params;
}

TEST(GroupMoves, NeverRaiseTheEnergyAndUsuallyReachTheMinimumOnThreeMeshEnergies) {
  // Three "meshes": overlap terms across meshes (odd cycles: QPBO cannot label them), seam
  // terms inside each; every move must be exact and improving or rejected.
  std::mt19937 rng(24);
  int optimal = 0;
  const int trials = 200;
  for (int trial = 0; trial < trials; ++trial) {
    const std::size_t n = 3 + rng() % 10;
    BinaryEnergy e;
    std::uniform_real_distribution<double> reward(-1.5, 0.3), w(0, 1);
    std::vector<std::uint32_t> group(n);
    for (std::size_t v = 0; v < n; ++v) {
      group[v] = static_cast<std::uint32_t>(v % 3);
      e.unary.push_back({0.0, reward(rng)});
    }
    for (std::size_t k = 0; k < 2 * n; ++k) {
      const auto i = static_cast<std::uint32_t>(rng() % n), j = static_cast<std::uint32_t>(rng() % n);
      if (i == j) continue;
      if (group[i] != group[j]) {
        e.pairs.push_back({i, j, 0, 0, 0, 10});
      } else {
        const double c = w(rng);
        e.pairs.push_back({i, j, 0, c, c, 0});
      }
    }
    std::vector<std::int8_t> x(n, 0);
    const double start = e.evaluate(x);
    const GroupMoveStats stats = improve_by_group_moves(e, group, x, sweeps(5));
    const double energy = e.evaluate(x);
    ASSERT_LE(energy, start + 1e-12) << "trial " << trial;
    ASSERT_EQ(stats.exact_moves, stats.moves) << "trial " << trial;  // no overlaps among the kept
    ASSERT_GE(energy, enumerate(e).minimum - 1e-9);
    optimal += energy <= enumerate(e).minimum + 1e-9 ? 1 : 0;
  }
  EXPECT_GT(optimal, trials * 8 / 10) << optimal;
}

/// A street-like energy: `n` variables of three meshes spread along a line, overlap terms
/// between nearby variables of different meshes, seam terms between nearby ones of the same.
struct StreetEnergy {
  BinaryEnergy energy;
  std::vector<std::uint32_t> group;
  std::vector<float> coordinate;  ///< along the street, 10 variables per unit
};
StreetEnergy street_energy(std::mt19937& rng, std::size_t n) {
  StreetEnergy street;
  auto& [e, group, coordinate] = street;
  std::uniform_real_distribution<double> reward(-1.5, 0.3), w(0, 1);
  std::uniform_real_distribution<float> where(0, float(n) / 10);
  for (std::size_t v = 0; v < n; ++v) {
    group.push_back(static_cast<std::uint32_t>(v % 3));
    coordinate.push_back(where(rng));
    e.unary.push_back({0.0, reward(rng)});
  }
  for (std::uint32_t i = 0; i < n; ++i) {
    for (std::uint32_t j = i + 1; j < n; ++j) {
      if (std::abs(coordinate[i] - coordinate[j]) > 0.5f || rng() % 4 != 0) continue;
      if (group[i] != group[j]) {
        e.pairs.push_back({i, j, 0, 0, 0, 10});
      } else {
        const double c = w(rng);
        e.pairs.push_back({i, j, 0, c, c, 0});
      }
    }
  }
  return street;
}

/// Group moves from the empty start on 1 and on 2 threads: both labellings, and the stats of
/// the run on 2. Expects the same labels on both and every move exact.
struct ThreadRuns {
  std::array<std::vector<std::int8_t>, 2> x;
  GroupMoveStats stats;
};
ThreadRuns on_one_and_two_threads(const BinaryEnergy& e, std::span<const std::uint32_t> group,
                                  const GroupMoveParams& params) {
  ThreadRuns out;
  for (const unsigned threads : {1u, 2u}) {
    const ThreadLimit limit(threads);
    std::vector<std::int8_t>& x = out.x[threads - 1];
    x.assign(e.size(), 0);
    out.stats = improve_by_group_moves(e, group, x, params);
  }
  EXPECT_EQ(out.x[0], out.x[1]) << "the thread count changed the labels";
  EXPECT_EQ(out.stats.exact_moves, out.stats.moves);
  return out;
}

TEST(GroupMoves, SlabsSolvedInParallelNeverRaiseTheEnergyAndDoNotDependOnTheThreadCountOrOnSolvingThemInTurn) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 20; ++trial) {
    const auto [e, group, coordinate] = street_energy(rng, 600);
    std::vector<std::int8_t> whole(e.size(), 0);
    improve_by_group_moves(e, group, whole, sweeps(3));
    GroupMoveParams params = sweeps(3);
    params.coordinate = coordinate;
    params.slabs = 4;
    params.border_hops = 2;
    const ThreadRuns split = on_one_and_two_threads(e, group, params);
    GroupMoveParams one_by_one = params;
    one_by_one.slabs_at_once = false;
    std::vector<std::int8_t> in_turn(e.size(), 0);
    improve_by_group_moves(e, group, in_turn, one_by_one);
    EXPECT_EQ(in_turn, split.x[0]) << "trial " << trial;  // slabs in turn: the same labels
    ASSERT_GT(split.stats.solves, split.stats.moves);  // slabs and borders, not one cut per move
    ASSERT_LE(e.evaluate(split.x[0]), 0.0);            // never above the empty start
    // Holding the borders fixed costs little against one cut per move.
    EXPECT_LE(e.evaluate(split.x[0]), e.evaluate(whole) + 0.02 * std::abs(e.evaluate(whole))) << "trial " << trial;
  }
}

/// Each of n variables open unless rng says 0 modulo `one_in`: the flags and the open ones.
struct OpenSet {
  std::vector<std::uint8_t> flags;
  std::vector<std::uint32_t> list;
};
OpenSet random_open(std::mt19937& rng, std::size_t n, unsigned one_in) {
  OpenSet out;
  out.flags.resize(n);
  for (std::uint32_t v = 0; v < n; ++v) {
    out.flags[v] = rng() % one_in != 0 ? 1 : 0;
    if (out.flags[v] != 0) out.list.push_back(v);
  }
  return out;
}

TEST(GroupMoves, NoTermJoinsTheInteriorsOfTwoSlabs) {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 20; ++trial) {
    const auto [e, group, coordinate] = street_energy(rng, 400);
    const mosaic_detail::PairIndex index(e);
    const auto [open, all] = random_open(rng, e.size(), 3);
    std::vector<std::uint32_t> slab(e.size());
    for (std::uint32_t v = 0; v < e.size(); ++v) {
      slab[v] = static_cast<std::uint32_t>(coordinate[v] / 10.0f);  // 4 slabs along the street
    }
    const mosaic_detail::SlabSplit split = mosaic_detail::split_by_slab(index, all, open, slab, 4);
    std::vector<int> where(e.size(), -2);  // -2 not listed, -1 border, else the interior's slab
    std::size_t listed = split.border.size();
    for (const std::uint32_t v : split.border) where[v] = -1;
    for (std::uint32_t s = 0; s < 4; ++s) {
      listed += split.interior[s].size();
      for (const std::uint32_t v : split.interior[s]) {
        ASSERT_EQ(slab[v], s);
        where[v] = static_cast<int>(s);
      }
    }
    ASSERT_EQ(listed, all.size());  // each open variable exactly once
    ASSERT_GT(split.border.size(), 0u);
    for (const auto& p : e.pairs) {
      if (where[p.i] >= 0 && where[p.j] >= 0) {
        ASSERT_EQ(where[p.i], where[p.j]) << "trial " << trial;
      }
    }
    for (const std::uint32_t v : split.border) {  // a border variable really reaches another slab
      bool reaches = false;
      for (const auto& p : e.pairs) {
        const std::uint32_t o = p.i == v ? p.j : p.j == v ? p.i : v;
        reaches = reaches || (o != v && open[o] != 0 && slab[o] != slab[v]);
      }
      ASSERT_TRUE(reaches);
    }
  }
}

TEST(GroupMoves, ThePairIndexListsEachVariablesTermsInOrderOnAnyThreadCount) {
  // Enough terms for the index to be built in blocks on two threads.
  std::mt19937 rng(41);
  const std::size_t n = 5000;
  BinaryEnergy e;
  e.unary.assign(n, {0, 0});
  std::uniform_real_distribution<double> u(-2, 2);
  std::vector<BinaryEnergy::Pair> terms;
  for (std::size_t k = 0; k < 300000; ++k) {
    const auto i = static_cast<std::uint32_t>(rng() % n), j = static_cast<std::uint32_t>(rng() % n);
    if (i != j) terms.push_back({i, j, u(rng), u(rng), u(rng), u(rng)});
  }
  // Runs of equal terms (as the mosaic's overlap terms are) across the blocks' borders (at
  // halves or quarters of the list), which share their values' rows.
  const std::size_t m = terms.size();
  for (const auto& [from, to] : {std::pair{20, 30}, std::pair{45, 55}, std::pair{70, 80}}) {
    for (std::size_t k = m * from / 100; k < m * to / 100; ++k) {
      std::tie(terms[k].e00, terms[k].e01, terms[k].e10, terms[k].e11) = std::tuple{0.0, 0.5, -0.25, 1.0};
    }
  }
  for (const BinaryEnergy::Pair& p : terms) e.pairs.push_back(p);
  // Brute force: each variable's terms in increasing order, and how many runs of one row
  // (of the energy's shared rows) they make.
  std::vector<std::vector<std::uint32_t>> rows(n);
  for (std::uint32_t k = 0; k < e.pairs.size(); ++k) {
    rows[e.pairs[k].i].push_back(k);
    rows[e.pairs[k].j].push_back(k);
  }
  std::size_t runs = 0;
  for (const std::vector<std::uint32_t>& r : rows) {
    for (std::size_t t = 0; t < r.size(); ++t) runs += t == 0 || e.pairs.row(r[t]) != e.pairs.row(r[t - 1]) ? 1 : 0;
  }
  // The equal terms share runs: at most one per variable and range of them.
  std::size_t equal = 0;
  for (const auto& p : terms) equal += p.e01 == 0.5 && p.e10 == -0.25 ? 1 : 0;
  ASSERT_GT(equal, m / 4);
  ASSERT_LE(runs, 2 * (m - equal) + 3 * n);
  const auto check = [&](const mosaic_detail::PairIndex& index, std::size_t blocks) {
    ASSERT_EQ(index.entries(), 2 * m);
    // A block may start a run its predecessor's last run continues: at most one per
    // variable and block border.
    ASSERT_GE(index.runs(), runs);
    ASSERT_LE(index.runs(), runs + (blocks - 1) * n);
    for (std::uint32_t v = 0; v < n; ++v) {
      std::vector<std::pair<std::uint32_t, std::array<double, 4>>> seen;
      index.for_each_term(v, [&](std::uint32_t end, const std::array<double, 4>& w) { seen.emplace_back(end, w); });
      ASSERT_EQ(seen.size(), rows[v].size()) << v;
      ASSERT_TRUE(std::ranges::equal(index.ends(v), seen | std::views::keys)) << v;
      for (std::size_t r = 0; r < rows[v].size(); ++r) {
        const auto& p = terms[rows[v][r]];
        const bool at_j = p.i != v;
        ASSERT_EQ(seen[r].first, at_j ? (p.i | mosaic_detail::PairIndex::kAtJ) : p.j);
        const std::array<double, 4> from_v =
            at_j ? std::array{p.e00, p.e10, p.e01, p.e11} : std::array{p.e00, p.e01, p.e10, p.e11};
        ASSERT_EQ(seen[r].second, from_v) << v << " term " << r;
      }
      // any_term stops at the first visit that says so.
      std::size_t visits = 0;
      const bool found = index.any_term(v, [&](std::uint32_t, const std::array<double, 4>&) { return ++visits == 2; });
      ASSERT_EQ(found, rows[v].size() >= 2);
      ASSERT_EQ(visits, std::min<std::size_t>(2, rows[v].size()));
    }
  };
  {
    const ThreadLimit one(1);
    check(mosaic_detail::PairIndex(e), 1);
  }
  check(mosaic_detail::PairIndex(e), std::min(4u, available_threads()));
}

TEST(Qpbo, FlipsAreFoundExactlyWhenSomeFlippingMakesEveryCouplingAttractive) {
  // Against brute force over every flipping: sparse pairs that attract (seams), repel
  // (overlaps) or do not couple, in any order; odd cycles anywhere in the list.
  std::mt19937 rng(31);
  int found = 0, refused = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    const std::size_t n = 2 + rng() % 9;
    BinaryEnergy e;
    e.unary.assign(n, {0, -1});
    const std::size_t pairs = rng() % (n + 3);
    for (std::size_t k = 0; k < pairs; ++k) {
      const auto i = static_cast<std::uint32_t>(rng() % n), j = static_cast<std::uint32_t>(rng() % n);
      if (i == j) continue;
      switch (rng() % 3) {
        case 0:
          e.pairs.push_back({i, j, 0, 1, 1, 0});
          break;  // attracts: coupling > 0
        case 1:
          e.pairs.push_back({i, j, 0, 0, 0, 1});
          break;  // repels: coupling < 0
        default:
          e.pairs.push_back({i, j, 1, 2, 3, 4});
          break;  // e01 + e10 = e00 + e11: no coupling
      }
    }
    const auto consistent = [&](std::uint32_t bits) {
      for (const auto& p : e.pairs) {
        const double c = p.e01 + p.e10 - p.e00 - p.e11;
        if (c != 0 && (((bits >> p.i) ^ (bits >> p.j)) & 1u) != (c < 0 ? 1u : 0u)) return false;
      }
      return true;
    };
    bool exists = false;
    for (std::uint32_t bits = 0; bits < (1u << n) && !exists; ++bits) exists = consistent(bits);
    const auto flips = submodular_flips(e);
    ASSERT_EQ(flips.has_value(), exists) << "trial " << trial;
    if (!flips) {
      ++refused;
      continue;
    }
    ++found;
    std::uint32_t bits = 0;
    for (std::size_t v = 0; v < n; ++v) bits |= std::uint32_t{(*flips)[v] != 0} << v;
    EXPECT_TRUE(consistent(bits)) << "trial " << trial;
    // Of the consistent flippings, the one that leaves the lowest variable of every connected
    // set of coupled variables unflipped (what a breadth-first colouring from each gives).
    std::vector<std::size_t> lowest(n);
    for (std::size_t v = 0; v < n; ++v) lowest[v] = v;
    for (bool moved = true; moved;) {
      moved = false;
      for (const auto& p : e.pairs) {
        if (p.e01 + p.e10 - p.e00 - p.e11 == 0) continue;
        const std::size_t m = std::min(lowest[p.i], lowest[p.j]);
        moved = moved || lowest[p.i] != m || lowest[p.j] != m;
        lowest[p.i] = lowest[p.j] = m;
      }
    }
    for (std::size_t v = 0; v < n; ++v) {
      if (lowest[v] == v) {
        EXPECT_EQ((*flips)[v], 0) << "trial " << trial << ", variable " << v;
      }
    }
  }
  EXPECT_GT(found, 200);
  EXPECT_GT(refused, 200);
}

TEST(PairList, GivesBackEachTermBitForBitAndSharesTheValuesOfEqualNeighboursOnly) {
  const std::vector<BinaryEnergy::Pair> terms{{0, 1, 0, 0, 0, 10},    {2, 3, 0, 0, 0, 10},
                                              {1, 2, 0, 0, 0, 10},                          // one row
                                              {0, 2, -0.0, 0, 0, 10},                       // -0 is not +0: its own row
                                              {3, 4, 0, 2.5, 2.5, 0}, {1, 4, 0, 0, 0, 10},  // a row each
                                              {2, 4, 0, 0, 0, 10}};                         // shares the row before it
  PairList list;
  for (const BinaryEnergy::Pair& p : terms) list.push_back(p);
  ASSERT_EQ(list.size(), terms.size());
  EXPECT_EQ(list.values().size(), 4u);
  const auto bits = [](const BinaryEnergy::Pair& p) {
    return std::array{std::uint64_t{p.i},
                      std::uint64_t{p.j},
                      std::bit_cast<std::uint64_t>(p.e00),
                      std::bit_cast<std::uint64_t>(p.e01),
                      std::bit_cast<std::uint64_t>(p.e10),
                      std::bit_cast<std::uint64_t>(p.e11)};
  };
  std::size_t k = 0;
  for (const BinaryEnergy::Pair p : list) {
    EXPECT_EQ(bits(p), bits(terms[k])) << k;
    EXPECT_EQ(list.variables(k), (std::array{terms[k].i, terms[k].j})) << k;
    ++k;
  }
  EXPECT_EQ(k, terms.size());
  // Indexed, walked backwards and jumped to: the same terms, on the same rows.
  for (auto it = list.end(); it != list.begin();) {
    --it;
    k = static_cast<std::size_t>(it - list.begin());
    EXPECT_EQ(bits(*it), bits(terms[k])) << k;
    EXPECT_EQ(bits(list[k]), bits(terms[k])) << k;
    EXPECT_EQ(it.row(), list.row(k)) << k;
    EXPECT_EQ(bits(list.begin()[static_cast<std::ptrdiff_t>(k)]), bits(terms[k])) << k;
  }
  EXPECT_EQ(list.row(0), 0u);
  EXPECT_EQ(list.row(list.size()), list.values().size() - 1);  // end()'s row: the last
  EXPECT_EQ(list.row(2), 0u);
  EXPECT_EQ(list.row(3), 1u);
  EXPECT_EQ(list.row(5), list.row(6));
  EXPECT_NE(list.row(2), list.row(3));
}

TEST(Qpbo, ThreeMutuallyOverlappingTrianglesCannotBeFlipped) {
  BinaryEnergy e;
  e.unary = {{0, -1}, {0, -1}, {0, -1}};
  for (const BinaryEnergy::Pair& p :
       {BinaryEnergy::Pair{0, 1, 0, 0, 0, 10}, {1, 2, 0, 0, 0, 10}, {0, 2, 0, 0, 0, 10}}) {
    e.pairs.push_back(p);
  }
  EXPECT_FALSE(submodular_flips(e).has_value());
  MinimiseStats stats;
  const std::vector<std::int8_t> x = minimise(e, {}, stats);
  EXPECT_FALSE(stats.exact);
  EXPECT_EQ(stats.unlabelled_after_qpbo, 3u);  // the symmetric odd cycle defeats roof duality
  EXPECT_DOUBLE_EQ(e.evaluate(x), -1.0);       // keep exactly one
}

TEST(GroupMoves, TheSeamRegionIsTheOpenVariablesWithinHopsOfADisagreement) {
  // Against distances relaxed over the pair list until nothing changes (Bellman-Ford), not
  // the pair index the region is grown on.
  std::mt19937 rng(31);
  for (int trial = 0; trial < 30; ++trial) {
    const auto [e, group, coordinate] = street_energy(rng, 300);
    const mosaic_detail::PairIndex index(e);
    std::vector<std::int8_t> x(e.size());
    for (std::int8_t& label : x) label = static_cast<std::int8_t>(rng() % 2);
    const auto [open, all] = random_open(rng, e.size(), 4);
    std::vector<std::uint8_t> mark(e.size(), 0);
    const auto hops = static_cast<std::uint32_t>(trial % 4);
    const std::vector<std::uint32_t> region = mosaic_detail::seam_region(index, x, all, open, hops, mark);
    constexpr std::uint32_t kFar = UINT32_MAX;
    std::vector<std::uint32_t> distance(e.size(), kFar);
    for (const auto& p : e.pairs) {  // seams: only terms that cost disagreement (seam terms here)
      if (p.e01 + p.e10 <= p.e00 + p.e11 || x[p.i] == x[p.j]) continue;
      if (open[p.i] != 0) distance[p.i] = 0;
      if (open[p.j] != 0) distance[p.j] = 0;
    }
    for (bool changed = true; changed;) {
      changed = false;
      for (const auto& p : e.pairs) {
        for (const auto& [from, to] : {std::pair{p.i, p.j}, std::pair{p.j, p.i}}) {
          if (distance[from] == kFar || open[to] == 0 || distance[to] <= distance[from] + 1) continue;
          distance[to] = distance[from] + 1;
          changed = true;
        }
      }
    }
    std::vector<std::uint32_t> expected;
    for (std::uint32_t v = 0; v < e.size(); ++v) {
      if (distance[v] <= hops) expected.push_back(v);
    }
    ASSERT_FALSE(expected.empty());
    ASSERT_EQ(region, expected) << "trial " << trial << ", " << hops << " hops";
    ASSERT_EQ(std::count(mark.begin(), mark.end(), 1), 0);  // the scratch is left clean
  }
}

TEST(GroupMoves, LaterSweepsNearTheSeamsNeverRaiseTheEnergyAndDoNotDependOnTheThreadCount) {
  std::mt19937 rng(13);
  int lower = 0;
  for (int trial = 0; trial < 20; ++trial) {
    const auto [e, group, coordinate] = street_energy(rng, 600);
    GroupMoveParams params = sweeps(3);
    params.coordinate = coordinate;
    params.slabs = 2;
    params.later_sweep_hops = 2;
    const ThreadRuns near = on_one_and_two_threads(e, group, params);
    // The same first sweep (slabs aside), then moves that only keep what lowers the energy.
    std::vector<std::int8_t> first_slabs(e.size(), 0);
    GroupMoveParams one = sweeps(1);
    one.coordinate = coordinate;
    one.slabs = 2;
    improve_by_group_moves(e, group, first_slabs, one);
    ASSERT_LE(e.evaluate(near.x[0]), e.evaluate(first_slabs) + 1e-9) << "trial " << trial;
    lower += e.evaluate(near.x[0]) < e.evaluate(first_slabs) - 1e-9 ? 1 : 0;
  }
  EXPECT_GT(lower, 0) << "the later sweeps never improved anything: the test says nothing";
}

}  // namespace
}  // namespace citymesh
