// SPDX-License-Identifier: MIT
// QPBO-I improvement of a partial labelling, and the minimisation strategy.
#include <algorithm>
#include <deque>
#include <random>

#include "citymesh/core/stopwatch.h"
#include "citymesh/mosaic/binary_energy.h"

namespace citymesh {

namespace {

/// Pair indices per variable.
struct PairIndex {
  std::vector<std::uint32_t> offsets, pairs;

  explicit PairIndex(const BinaryEnergy& e) : offsets(e.size() + 1, 0) {
    for (const auto& p : e.pairs) {
      ++offsets[p.i + 1];
      ++offsets[p.j + 1];
    }
    for (std::size_t i = 0; i < e.size(); ++i) offsets[i + 1] += offsets[i];
    pairs.resize(offsets.back());
    std::vector<std::uint32_t> fill(offsets.begin(), offsets.end() - 1);
    for (std::uint32_t k = 0; k < e.pairs.size(); ++k) {
      pairs[fill[e.pairs[k].i]++] = k;
      pairs[fill[e.pairs[k].j]++] = k;
    }
  }
  [[nodiscard]] std::span<const std::uint32_t> of(std::uint32_t v) const {
    return {pairs.data() + offsets[v], pairs.data() + offsets[v + 1]};
  }
};

/// Cost of v taking label `l` given every other variable's label in x.
double local_cost(const BinaryEnergy& e, const PairIndex& index, std::span<const std::int8_t> x, std::uint32_t v,
                  bool l) {
  double c = e.unary[v][l ? 1 : 0];
  for (const std::uint32_t k : index.of(v)) {
    const auto& p = e.pairs[k];
    c += p.i == v ? p.value(l, x[p.j] != 0) : p.value(x[p.i] != 0, l);
  }
  return c;
}

/// Sets every unlabelled variable to its best label given the others, sweep after sweep,
/// until nothing changes (iterated conditional modes).
void complete_by_icm(const BinaryEnergy& e, const PairIndex& index, std::span<const std::uint32_t> free,
                     std::vector<std::int8_t>& x) {
  for (const std::uint32_t v : free) x[v] = e.unary[v][1] < e.unary[v][0] ? 1 : 0;
  for (int sweep = 0; sweep < 50; ++sweep) {
    bool changed = false;
    for (const std::uint32_t v : free) {
      const auto best = static_cast<std::int8_t>(local_cost(e, index, x, v, true) < local_cost(e, index, x, v, false));
      if (best != x[v]) {
        x[v] = best;
        changed = true;
      }
    }
    if (!changed) break;
  }
}

/// Connected groups of the variables in `free` (linked by pairs with both ends free).
std::vector<std::vector<std::uint32_t>> free_components(const BinaryEnergy& e, const PairIndex& index,
                                                        std::span<const std::uint32_t> free) {
  std::vector<std::uint8_t> is_free(e.size(), 0), seen(e.size(), 0);
  for (const std::uint32_t v : free) is_free[v] = 1;
  std::vector<std::vector<std::uint32_t>> components;
  for (const std::uint32_t s : free) {
    if (seen[s] != 0) continue;
    std::vector<std::uint32_t>& c = components.emplace_back();
    seen[s] = 1;
    c.push_back(s);
    for (std::size_t head = 0; head < c.size(); ++head) {
      for (const std::uint32_t k : index.of(c[head])) {
        const std::uint32_t o = e.pairs[k].i == c[head] ? e.pairs[k].j : e.pairs[k].i;
        if (is_free[o] != 0 && seen[o] == 0) {
          seen[o] = 1;
          c.push_back(o);
        }
      }
    }
  }
  return components;
}

/// The energy of the variables flagged in `open` with every other variable fixed to x;
/// `local` receives the variables in order (local index -> variable).
BinaryEnergy restricted(const BinaryEnergy& e, const PairIndex& index, std::span<const std::int8_t> x,
                        std::span<const std::uint32_t> open, std::vector<std::uint32_t>& to_local) {
  BinaryEnergy r;
  r.unary.resize(open.size());
  for (std::uint32_t l = 0; l < open.size(); ++l) to_local[open[l]] = l;
  for (std::uint32_t l = 0; l < open.size(); ++l) {
    const std::uint32_t v = open[l];
    r.unary[l] = e.unary[v];
    for (const std::uint32_t k : index.of(v)) {
      const auto& p = e.pairs[k];
      const std::uint32_t o = p.i == v ? p.j : p.i;
      if (to_local[o] != UINT32_MAX) {
        if (p.i == v) r.pairs.push_back({l, to_local[o], p.e00, p.e01, p.e10, p.e11});  // once, from its i end
        continue;
      }
      for (int b = 0; b < 2; ++b) r.unary[l][static_cast<std::size_t>(b)] += p.i == v ? p.value(b != 0, x[o] != 0)
                                                                                       : p.value(x[o] != 0, b != 0);
    }
  }
  for (const std::uint32_t v : open) to_local[v] = UINT32_MAX;
  return r;
}

/// Energy terms touching the component (unaries of its variables, pairs with an end in it).
double component_energy(const BinaryEnergy& e, const PairIndex& index, std::span<const std::int8_t> x,
                        std::span<const std::uint32_t> component, std::vector<std::uint8_t>& mark) {
  double sum = 0;
  for (const std::uint32_t v : component) mark[v] = 1;
  for (const std::uint32_t v : component) {
    sum += e.unary[v][static_cast<std::size_t>(x[v])];
    for (const std::uint32_t k : index.of(v)) {
      const auto& p = e.pairs[k];
      const std::uint32_t o = p.i == v ? p.j : p.i;
      if (mark[o] != 0 && o < v) continue;  // both ends inside: counted once
      sum += p.value(x[p.i] != 0, x[p.j] != 0);
    }
  }
  for (const std::uint32_t v : component) mark[v] = 0;
  return sum;
}

/// One QPBO-I pass over a component: fix a chunk of its still-open variables (in `order`) to
/// their value in y, run QPBO on the rest, take every label it gives, until none is open.
void qpbo_i_pass(const BinaryEnergy& e, const PairIndex& index, std::span<const std::uint32_t> order,
                 std::vector<std::int8_t>& y, std::vector<std::uint32_t>& to_local) {
  std::vector<std::uint32_t> open(order.begin(), order.end());
  while (!open.empty()) {
    const std::size_t fix = std::max<std::size_t>(1, open.size() / 8);
    open.erase(open.begin(), open.begin() + static_cast<std::ptrdiff_t>(fix));
    if (open.empty()) break;
    const BinaryEnergy sub = restricted(e, index, y, open, to_local);
    const std::vector<std::int8_t> labels = qpbo(sub);
    std::vector<std::uint32_t> still;
    for (std::size_t l = 0; l < open.size(); ++l) {
      if (labels[l] == kUnlabelled) {
        still.push_back(open[l]);
      } else {
        y[open[l]] = labels[l];
      }
    }
    open.swap(still);
  }
}

}  // namespace

std::vector<std::int8_t> improve_qpbo_i(const BinaryEnergy& e, std::span<const std::int8_t> partial,
                                        const ImproveParams& params, double* completed_energy) {
  const PairIndex index(e);
  std::vector<std::int8_t> x(partial.begin(), partial.end());
  std::vector<std::uint32_t> free;
  for (std::uint32_t v = 0; v < x.size(); ++v) {
    if (x[v] == kUnlabelled) free.push_back(v);
  }
  if (free.empty()) return x;
  complete_by_icm(e, index, free, x);
  if (completed_energy != nullptr) *completed_energy = e.evaluate(x);
  std::mt19937_64 rng(params.seed);
  std::vector<std::uint32_t> to_local(e.size(), UINT32_MAX);
  std::vector<std::uint8_t> mark(e.size(), 0);
  for (const std::vector<std::uint32_t>& component : free_components(e, index, free)) {
    double best = component_energy(e, index, x, component, mark);
    std::vector<std::uint32_t> order = component;
    std::vector<std::int8_t> kept(component.size());
    for (int round = 0; round < params.rounds; ++round) {
      std::shuffle(order.begin(), order.end(), rng);
      // The pass changes only this component's variables: keep their values to undo it.
      for (std::size_t k = 0; k < component.size(); ++k) kept[k] = x[component[k]];
      qpbo_i_pass(e, index, order, x, to_local);
      const double candidate = component_energy(e, index, x, component, mark);
      if (candidate <= best) {
        best = candidate;
      } else {
        for (std::size_t k = 0; k < component.size(); ++k) x[component[k]] = kept[k];
      }
    }
  }
  return x;
}

GroupMoveStats improve_by_group_moves(const BinaryEnergy& e, std::span<const std::uint32_t> group,
                                      std::vector<std::int8_t>& x, int max_sweeps) {
  const PairIndex index(e);
  GroupMoveStats stats;
  const std::uint32_t groups = group.empty() ? 0 : *std::max_element(group.begin(), group.end()) + 1;
  std::vector<std::uint32_t> to_local(e.size(), UINT32_MAX);
  for (int sweep = 0; sweep < max_sweeps; ++sweep) {
    ++stats.sweeps;
    bool changed = false;
    for (std::uint32_t k = 0; k < groups; ++k) {
      std::vector<std::uint32_t> open;
      for (std::uint32_t v = 0; v < e.size(); ++v) {
        if (group[v] == k || x[v] == 1) open.push_back(v);
      }
      if (open.empty()) continue;
      ++stats.moves;
      const BinaryEnergy sub = restricted(e, index, x, open, to_local);
      std::vector<std::int8_t> y;
      if (const auto flips = submodular_flips(sub)) {
        y = minimise_by_flipped_cut(sub, *flips);
        ++stats.exact_moves;
      } else {
        y = qpbo(sub);  // persistent labels only; the others keep their value
        for (std::size_t l = 0; l < y.size(); ++l) {
          if (y[l] == kUnlabelled) y[l] = x[open[l]];
        }
      }
      // The restricted energy differs from the whole one by a constant: compare there.
      std::vector<std::int8_t> now(open.size());
      for (std::size_t l = 0; l < open.size(); ++l) now[l] = x[open[l]];
      const double before = sub.evaluate(now), after = sub.evaluate(y);
      if (after < before - 1e-9 * (1 + std::abs(before))) {
        for (std::size_t l = 0; l < open.size(); ++l) x[open[l]] = y[l];
        ++stats.improving_moves;
        changed = true;
      }
    }
    if (!changed) break;
  }
  return stats;
}

std::vector<std::int8_t> minimise(const BinaryEnergy& e, const ImproveParams& params, MinimiseStats& stats) {
  Stopwatch clock;
  if (const auto flips = submodular_flips(e)) {
    std::vector<std::int8_t> x = minimise_by_flipped_cut(e, *flips);
    stats.exact = true;
    stats.energy = stats.energy_before_improvement = e.evaluate(x);
    stats.seconds_qpbo = clock.seconds();
    return x;
  }
  const std::vector<std::int8_t> partial = qpbo(e);
  stats.unlabelled_after_qpbo = static_cast<std::size_t>(std::count(partial.begin(), partial.end(), kUnlabelled));
  stats.seconds_qpbo = clock.restart();
  std::vector<std::int8_t> x = improve_qpbo_i(e, partial, params, &stats.energy_before_improvement);
  stats.seconds_improvement = clock.seconds();
  stats.energy = e.evaluate(x);
  return x;
}

}  // namespace citymesh
