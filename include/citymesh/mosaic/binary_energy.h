// SPDX-License-Identifier: MIT
// A pseudo-boolean energy of unary and pairwise terms over binary variables, and the ways we
// minimise it: an exact graph cut when flipping some variables makes every term submodular,
// otherwise QPBO (roof duality: a max-flow on the doubled graph, keeping only the strongly
// persistent labels) followed by QPBO-I improvement of the unlabelled variables.
#pragma once

#include <array>
#include <bit>
#include <compare>
#include <cstddef>
#include <cstdint>
#include <iterator>
#include <optional>
#include <span>
#include <vector>

namespace citymesh {

/// A pairwise term e[x_i][x_j] of two distinct variables.
struct EnergyPair {
  std::uint32_t i = 0, j = 0;
  double e00 = 0, e01 = 0, e10 = 0, e11 = 0;
  [[nodiscard]] bool submodular() const { return e00 + e11 <= e01 + e10; }
  [[nodiscard]] double value(bool xi, bool xj) const { return xi ? (xj ? e11 : e10) : (xj ? e01 : e00); }
};

/// The pairwise terms of an energy, in the order they were added, kept compactly: each term's
/// two variables, and rows of values {e00, e01, e10, e11}, each shared by a run of consecutive
/// terms whose values are equal bit for bit (a row holds where its run starts). The mosaic's
/// overlap terms all have the same values and a spinning scanner's tile holds ~28 of them per
/// variable: 8 bytes a term instead of 40 (a term read back is the one added, bit for bit).
/// Walk the terms in order (the iterator keeps its row); indexing, or an iterator made
/// elsewhere than at begin() or end(), finds the row by bisection.
class PairList {
 public:
  /// Reads a term back, by value (the list holds no EnergyPair).
  class Iterator {
   public:
    using iterator_category = std::random_access_iterator_tag;
    using value_type = EnergyPair;
    using difference_type = std::ptrdiff_t;
    using pointer = void;
    using reference = EnergyPair;
    Iterator() = default;
    Iterator(const PairList* list, std::size_t k) : list_(list), k_(k), row_(list->row(k)) {}
    EnergyPair operator*() const { return list_->term(k_, row_); }
    EnergyPair operator[](difference_type d) const { return *(*this + d); }
    Iterator& operator++() {
      ++k_;
      if (row_ + 1 < list_->row_starts_.size() && list_->row_starts_[row_ + 1] <= k_) ++row_;
      return *this;
    }
    Iterator operator++(int) {
      const Iterator old = *this;
      ++*this;
      return old;
    }
    Iterator& operator--() {
      --k_;
      if (list_->row_starts_[row_] > k_) --row_;
      return *this;
    }
    Iterator operator--(int) {
      const Iterator old = *this;
      --*this;
      return old;
    }
    Iterator& operator+=(difference_type d) {
      k_ = static_cast<std::size_t>(static_cast<difference_type>(k_) + d);
      row_ = list_->row(k_);
      return *this;
    }
    Iterator& operator-=(difference_type d) { return *this += -d; }
    friend Iterator operator+(Iterator it, difference_type d) { return it += d; }
    friend Iterator operator+(difference_type d, Iterator it) { return it += d; }
    friend Iterator operator-(Iterator it, difference_type d) { return it -= d; }
    friend difference_type operator-(const Iterator& a, const Iterator& b) {
      return static_cast<difference_type>(a.k_) - static_cast<difference_type>(b.k_);
    }
    friend bool operator==(const Iterator& a, const Iterator& b) { return a.k_ == b.k_; }
    friend auto operator<=>(const Iterator& a, const Iterator& b) { return a.k_ <=> b.k_; }
    /// The term's variables {i, j}, without its values.
    [[nodiscard]] std::array<std::uint32_t, 2> variables() const { return list_->variables(k_); }
    /// The term's row of values().
    [[nodiscard]] std::uint32_t row() const { return row_; }

   private:
    const PairList* list_ = nullptr;
    std::size_t k_ = 0;
    std::uint32_t row_ = 0;
  };

  /// Inline: the group moves add every term of each restricted energy (2 % of a tile's
  /// instructions out of line).
  void push_back(const EnergyPair& p) {
    if (ends_.size() >= UINT32_MAX) too_many_terms();
    if (rows_.empty() || !same_bits(rows_.back(), p)) {
      rows_.push_back({p.e00, p.e01, p.e10, p.e11});
      row_starts_.push_back(static_cast<std::uint32_t>(ends_.size()));
    }
    ends_.push_back({p.i, p.j});
  }
  /// Room for `terms` terms, and for `rows` distinct rows of values when known.
  void reserve(std::size_t terms, std::size_t rows = 0) {
    ends_.reserve(terms);
    rows_.reserve(rows);
    row_starts_.reserve(rows);
  }
  void clear() {
    ends_.clear();
    rows_.clear();
    row_starts_.clear();
  }
  [[nodiscard]] std::size_t size() const { return ends_.size(); }
  [[nodiscard]] bool empty() const { return ends_.empty(); }
  /// Term k (its row found by bisection: walk with an iterator instead).
  [[nodiscard]] EnergyPair operator[](std::size_t k) const { return term(k, row(k)); }
  [[nodiscard]] Iterator begin() const { return {this, 0}; }
  [[nodiscard]] Iterator end() const { return {this, size()}; }
  /// Term k's variables {i, j}, without its values.
  [[nodiscard]] std::array<std::uint32_t, 2> variables(std::size_t k) const { return {ends_[k].i, ends_[k].j}; }
  /// Term k's row of values(), which equal consecutive terms share (by bisection; the last
  /// row for k = size()).
  [[nodiscard]] std::uint32_t row(std::size_t k) const;
  /// The distinct rows of values {e00, e01, e10, e11}; a later term's row is never before an
  /// earlier term's.
  [[nodiscard]] std::span<const std::array<double, 4>> values() const { return rows_; }

 private:
  struct Ends {
    std::uint32_t i, j;
  };
  /// Equal bit for bit (so -0.0 and 0.0 differ, and a NaN equals itself).
  static bool same_bits(const std::array<double, 4>& row, const EnergyPair& p) {
    const auto bits = [](double v) { return std::bit_cast<std::uint64_t>(v); };
    return bits(row[0]) == bits(p.e00) && bits(row[1]) == bits(p.e01) && bits(row[2]) == bits(p.e10) &&
           bits(row[3]) == bits(p.e11);
  }
  [[noreturn]] static void too_many_terms();
  [[nodiscard]] EnergyPair term(std::size_t k, std::uint32_t row) const {
    const std::array<double, 4>& w = rows_[row];
    return {ends_[k].i, ends_[k].j, w[0], w[1], w[2], w[3]};
  }
  std::vector<Ends> ends_;
  std::vector<std::array<double, 4>> rows_;
  std::vector<std::uint32_t> row_starts_;  ///< per row: its first term
};

/// E(x) = sum_i unary[i][x_i] + sum_(i,j) e[x_i][x_j].
struct BinaryEnergy {
  using Pair = EnergyPair;
  std::vector<std::array<double, 2>> unary;
  PairList pairs;

  [[nodiscard]] std::size_t size() const { return unary.size(); }
  /// E(x) for a complete labelling (every entry 0 or 1).
  [[nodiscard]] double evaluate(std::span<const std::int8_t> x) const;
  /// The energies of x and of y in one pass over the terms, each summed as evaluate() would.
  [[nodiscard]] std::array<double, 2> evaluate(std::span<const std::int8_t> x, std::span<const std::int8_t> y) const;
};

/// Label of a variable: 0, 1, or unlabelled.
constexpr std::int8_t kUnlabelled = -1;

/// Variables to flip (x -> 1 - x) so that every pairwise term becomes submodular, when such a
/// set exists (a two-colouring of the pair graph where non-submodular pairs join different
/// colours and submodular ones equal colours); nullopt when it does not. With two meshes and
/// overlap terms between them only, flipping one mesh is such a set.
std::optional<std::vector<std::uint8_t>> submodular_flips(const BinaryEnergy& e);

/// True when flipping the variables in `flips` makes every pairwise term submodular (the
/// test submodular_flips() applies to the set it finds): a cheap check of a known candidate.
bool flips_make_submodular(const BinaryEnergy& e, std::span<const std::uint8_t> flips);

/// The s-t graph whose minimum cut minimises an energy: node i is x_i (source side: 0); with
/// `doubled`, node n + i is its negation (QPBO's construction), else every term must be
/// submodular. Terms are split so that unary parts stay balanced (fewer augmentations).
struct CutGraph {
  struct Arc {
    std::uint32_t from = 0, to = 0;
    double capacity = 0, reverse_capacity = 0;  ///< from -> to, and to -> from
  };
  std::size_t nodes = 0;
  std::vector<std::array<double, 2>> terminal;  ///< per node: from the source, to the sink
  std::vector<Arc> arcs;
};
/// With `flips` (one flag per variable), the graph of the energy flipped there.
CutGraph cut_graph(const BinaryEnergy& e, bool doubled, std::span<const std::uint8_t> flips = {});

/// Exact minimum of an energy whose terms are all submodular once the variables in `flips`
/// are flipped: one graph cut. Returns a complete labelling.
std::vector<std::int8_t> minimise_by_flipped_cut(const BinaryEnergy& e, std::span<const std::uint8_t> flips);

/// QPBO: the strongly persistent partial labelling (every labelled variable takes that label
/// in every global minimum); the others are kUnlabelled.
std::vector<std::int8_t> qpbo(const BinaryEnergy& e);

struct ImproveParams {
  int rounds = 3;          ///< random orders tried
  std::uint64_t seed = 1;  ///< fixed: the same input gives the same labelling
};

/// QPBO-I (Rother et al. 2007): completes a partial labelling (unlabelled variables first set
/// by iterated conditional modes), then repeatedly fixes unlabelled variables, in a random
/// order, to their current value and re-runs QPBO on the unlabelled part; the new labels are
/// kept when the energy does not rise. Never returns a labelling worse than its start (the
/// completed one, whose energy goes to `completed_energy` when given).
std::vector<std::int8_t> improve_qpbo_i(const BinaryEnergy& e, std::span<const std::int8_t> partial,
                                        const ImproveParams& params, double* completed_energy = nullptr);

struct GroupMoveParams {
  int max_sweeps = 2;
  /// One coordinate per variable (a triangle's centroid along the scene's longest axis), or
  /// empty. With it, every move is cut into `slabs` slabs of equal variable counts along the
  /// coordinate, solved in parallel; the variables with a term reaching into another slab are
  /// held fixed meanwhile and re-solved afterwards, with their neighbourhood up to
  /// `border_hops` terms away. The slabs depend on the coordinates only, never on the thread
  /// count, so the result does not either.
  std::span<const float> coordinate;
  std::uint32_t slabs = 1;
  std::uint32_t border_hops = 16;
  /// Sweeps after the first re-solve each group only within this many terms of a seam (a
  /// term that costs disagreement joining variables of different labels): the first sweep
  /// has placed the pieces, later ones mostly move their edges. 0: everywhere, every sweep.
  std::uint32_t later_sweep_hops = 0;
  /// Solves the slab interiors at the same time (false: one after another, with one
  /// max-flow graph alive instead of one per slab; the same result).
  bool slabs_at_once = true;
};

struct GroupMoveStats {
  std::size_t moves = 0, exact_moves = 0, improving_moves = 0, sweeps = 0;
  std::size_t solves = 0;  ///< restricted energies solved: one per move, or its slabs and borders
};

/// Group moves, a QPBO-I whose fixed set is chosen so that the re-solve is exact: `group`
/// gives each variable a group (a mesh) with no non-submodular term inside a group. For each
/// group k in turn, the variables of k and the variables of other groups now at 1 are
/// re-solved together, every other variable fixed to its value in x. With overlap-like terms
/// (non-submodular only across groups, and none among the variables at 1) that restricted
/// energy flips to submodular and one cut solves it exactly; otherwise QPBO's persistent
/// labels of it are taken. A re-solve is kept only when it lowers the energy, so x never gets
/// worse. Sweeps over the groups until a sweep changes nothing or `max_sweeps`; sweeps after
/// the first near the seams only, with `later_sweep_hops`.
GroupMoveStats improve_by_group_moves(const BinaryEnergy& e, std::span<const std::uint32_t> group,
                                      std::vector<std::int8_t>& x, const GroupMoveParams& params);

struct MinimiseStats {
  bool exact = false;  ///< solved by one cut after flipping
  std::size_t unlabelled_after_qpbo = 0;
  double energy_before_improvement = 0;  ///< QPBO's labels completed by ICM
  double energy = 0;
  double seconds_qpbo = 0, seconds_improvement = 0;
};

/// The whole strategy: exact flipped cut when possible, else QPBO then QPBO-I.
std::vector<std::int8_t> minimise(const BinaryEnergy& e, const ImproveParams& params, MinimiseStats& stats);

}  // namespace citymesh
