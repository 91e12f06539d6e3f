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

/// The pair terms of each variable (compressed rows): per entry the term's other end and its
/// values seen from this end, so that a walk over neighbours or a restricted energy reads
/// memory in order instead of loading pairs at random (that cut the restricted energies' time
/// by 60 %). The values are the energy's rows (PairList), each held twice (seen from i, from
/// j), not four doubles per entry: a spinning scanner's tile holds about 12 overlap terms per
/// variable, all with the same values (80 bytes a term when each entry held its own values;
/// 16 now). Pairs must join two distinct variables.
struct PairIndex {
  static constexpr std::uint32_t kAtJ = 1u << 31;  ///< in `ends`: the variable is the pair's j
  std::vector<std::uint32_t> offsets;
  std::vector<std::uint32_t> ends;        ///< per entry: the other end, | kAtJ when the variable is j
  std::vector<std::uint32_t> value_rows;  ///< per entry: its row of `rows`
  /// Rows 2r and 2r + 1: the energy's r-th row of values {e00, e01, e10, e11} seen from i, and
  /// seen from j ({e00, e10, e01, e11}).
  std::vector<std::array<double, 4>> rows;

  explicit PairIndex(const BinaryEnergy& e);
  /// The entry's pair values e[this end][other end], at index 2 * (this end) + (other end).
  [[nodiscard]] const std::array<double, 4>& values(std::uint32_t entry) const { return rows[value_rows[entry]]; }
  [[nodiscard]] static std::uint32_t variable(std::uint32_t end) { return end & ~kAtJ; }
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
