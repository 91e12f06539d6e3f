// SPDX-License-Identifier: MIT
// QPBO-I improvement of a partial labelling, and the minimisation strategy.
#include <algorithm>
#include <random>

#include "citymesh/core/stopwatch.h"
#include "citymesh/mosaic/binary_energy.h"
#include "restricted_energy.h"

namespace citymesh {

using mosaic_detail::PairIndex;
using mosaic_detail::restricted;

namespace {

/// Cost of v taking label `l` given every other variable's label in x.
double local_cost(const BinaryEnergy& e, const PairIndex& index, std::span<const std::int8_t> x, std::uint32_t v,
                  bool l) {
  double c = e.unary[v][l ? 1 : 0];
  index.for_each_term(v, [&](std::uint32_t end, const PairIndex::Values& w) {
    c += w[(l ? 2 : 0) + (x[PairIndex::variable(end)] != 0 ? 1 : 0)];
  });
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
      for (const std::uint32_t end : index.ends(c[head])) {
        const std::uint32_t o = PairIndex::variable(end);
        if (is_free[o] != 0 && seen[o] == 0) {
          seen[o] = 1;
          c.push_back(o);
        }
      }
    }
  }
  return components;
}

/// Energy terms touching the component (unaries of its variables, pairs with an end in it).
double component_energy(const BinaryEnergy& e, const PairIndex& index, std::span<const std::int8_t> x,
                        std::span<const std::uint32_t> component, std::vector<std::uint8_t>& mark) {
  double sum = 0;
  for (const std::uint32_t v : component) mark[v] = 1;
  for (const std::uint32_t v : component) {
    sum += e.unary[v][static_cast<std::size_t>(x[v])];
    index.for_each_term(v, [&](std::uint32_t end, const PairIndex::Values& w) {
      const std::uint32_t o = PairIndex::variable(end);
      if (mark[o] != 0 && o < v) return;  // both ends inside: counted once
      sum += w[(x[v] != 0 ? 2 : 0) + (x[o] != 0 ? 1 : 0)];
    });
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
