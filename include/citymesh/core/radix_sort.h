// SPDX-License-Identifier: MIT
#pragma once

#include <cstdint>
#include <span>
#include <utility>

namespace citymesh {

/// Sorts pairs ascending (first, then second), as std::sort with std::less would, by a least
/// significant digit radix sort: linear time, and digits on which every key agrees are
/// skipped, so keys bounded by a triangle count cost four short passes. From a million pairs
/// on, the pairs are first split in place by their highest digit, and only the parts need a
/// buffer: the extra memory is a fraction of the pairs' own. Single-threaded: on the million
/// pairs of a detect step it beats a parallel comparison sort on two cores several times over.
void radix_sort_pairs(std::span<std::pair<std::uint32_t, std::uint32_t>> values);

/// Sorts pairs by `first` only, keeping the order of pairs with equal firsts (stable): the
/// same as radix_sort_pairs() when the pairs come ordered by `second`, such as (key, index)
/// pairs made in index order, in half the passes.
void stable_radix_sort_by_first(std::span<std::pair<std::uint32_t, std::uint32_t>> values);

}  // namespace citymesh
