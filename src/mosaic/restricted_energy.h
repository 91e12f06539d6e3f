// SPDX-License-Identifier: MIT
// Pieces of a binary energy shared by the solvers that re-solve part of it (QPBO-I, group
// moves): which pairs touch each variable, and the energy of a subset of the variables with
// every other one fixed.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "citymesh/mosaic/binary_energy.h"

namespace citymesh::mosaic_detail {

/// The pair terms of each variable (compressed rows): per entry the term's other end, so that
/// a walk over neighbours or a restricted energy reads memory in order instead of loading
/// pairs at random (that cut the restricted energies' time by 60 %). The values are not held
/// per entry: a variable's entries come in term order, where the energy's rows of values
/// only grow, so each variable keeps runs of entries sharing a row (a spinning scanner's tile
/// holds ~28 overlap terms per variable, all one row, and ~3 seam terms with their own: the
/// index went from 16 bytes an entry with the rows held twice to 4 bytes plus 8 per run,
/// 955 -> 448 MB on its largest tile). Pairs must join two distinct variables. The index
/// reads the energy's rows: it is valid while the energy lives, unchanged.
class PairIndex {
 public:
  static constexpr std::uint32_t kAtJ = 1u << 31;  ///< in an end: this variable is the pair's j
  using Values = std::array<double, 4>;

  explicit PairIndex(const BinaryEnergy& e);

  /// Calls visit(end, values) for each of v's terms in term order, until it returns true;
  /// `end` is the other variable, | kAtJ when v is the term's j, and `values` the term seen
  /// from v: e[x_v][x_other] at 2 * x_v + x_other. Returns whether a visit returned true.
  template <class Visit>
  bool any_term(std::uint32_t v, Visit&& visit) const {
    const std::uint32_t last_run = run_offsets_[v + 1];
    for (std::uint32_t run = run_offsets_[v]; run < last_run; ++run) {
      const Values& w = rows_[runs_[run].row];
      const Values from_i = w, from_j{w[0], w[2], w[1], w[3]};  // seen from j, e01 and e10 trade places
      const std::uint32_t run_end = run + 1 < last_run ? runs_[run + 1].first_entry : offsets_[v + 1];
      for (std::uint32_t entry = runs_[run].first_entry; entry < run_end; ++entry) {
        const std::uint32_t end = ends_[entry];
        if (visit(end, (end & kAtJ) != 0 ? from_j : from_i)) return true;
      }
    }
    return false;
  }
  /// any_term() for a visit that returns nothing: every term.
  template <class Visit>
  void for_each_term(std::uint32_t v, Visit&& visit) const {
    any_term(v, [&](std::uint32_t end, const Values& w) { return visit(end, w), false; });
  }
  /// v's other ends (| kAtJ as in any_term), in term order, without values.
  [[nodiscard]] std::span<const std::uint32_t> ends(std::uint32_t v) const {
    return std::span(ends_).subspan(offsets_[v], offsets_[v + 1] - offsets_[v]);
  }
  [[nodiscard]] static std::uint32_t variable(std::uint32_t end) { return end & ~kAtJ; }
  [[nodiscard]] std::size_t entries() const { return ends_.size(); }
  [[nodiscard]] std::size_t runs() const { return runs_.size(); }

 private:
  struct Run {
    std::uint32_t first_entry, row;  ///< the run's first entry; its row of the energy's values
  };
  std::vector<std::uint32_t> offsets_;      ///< per variable + 1: where its entries start
  std::vector<std::uint32_t> ends_;         ///< per entry: the other end, | kAtJ
  std::vector<std::uint32_t> run_offsets_;  ///< per variable + 1: where its runs start
  std::vector<Run> runs_;
  std::span<const Values> rows_;  ///< the energy's rows, as added (seen from i)
};

/// The energy of the variables in `open` with every other variable fixed to its value in x;
/// local variable l is open[l]. `to_local` is scratch: e.size() entries, all UINT32_MAX, and
/// left so.
BinaryEnergy restricted(const BinaryEnergy& e, const PairIndex& index, std::span<const std::int8_t> x,
                        std::span<const std::uint32_t> open, std::vector<std::uint32_t>& to_local);

/// `seeds` (distinct) and the variables flagged in `open` up to `hops` terms from them, through
/// flagged variables; ascending. `mark` is scratch: one zero per variable, left so.
std::vector<std::uint32_t> grow_region(const PairIndex& index, std::vector<std::uint32_t> seeds,
                                       std::span<const std::uint8_t> open, std::uint32_t hops,
                                       std::vector<std::uint8_t>& mark);

/// The variables of `all` (flagged in `open`) within `hops` terms of a seam of x: a variable
/// of `all` joined by a term that costs disagreement (e01 + e10 > e00 + e11) to a variable of
/// the other label is on a seam; the region grows from those through flagged variables.
/// Ascending. `mark` as for grow_region.
std::vector<std::uint32_t> seam_region(const PairIndex& index, std::span<const std::int8_t> x,
                                       std::span<const std::uint32_t> all, std::span<const std::uint8_t> open,
                                       std::uint32_t hops, std::vector<std::uint8_t>& mark);

/// The variables `all` (flagged in `open`, one flag per variable) cut by `slab` (one per
/// variable, < slabs): per slab its interior, the variables with no pair term reaching an
/// open variable of another slab, and the border, all the others. No term joins the
/// interiors of two slabs, so they can be re-solved at the same time. Lists keep the order of
/// `all`.
struct SlabSplit {
  std::vector<std::vector<std::uint32_t>> interior;
  std::vector<std::uint32_t> border;
};
SlabSplit split_by_slab(const PairIndex& index, std::span<const std::uint32_t> all, std::span<const std::uint8_t> open,
                        std::span<const std::uint32_t> slab, std::uint32_t slabs);

}  // namespace citymesh::mosaic_detail
