// SPDX-License-Identifier: MIT
// The vertices of several keyed pieces, each key once (merging pieces, cutting a part out).
#pragma once

#include <algorithm>
#include <cstdint>
#include <span>
#include <vector>

#include "citymesh/core/keyed_piece.h"

namespace citymesh {

/// Every vertex of the pieces once, in key order, and where each piece's vertices fall in
/// that order.
struct KeyUnion {
  std::vector<std::uint64_t> keys;
  std::vector<std::vector<std::uint32_t>> of_piece;  ///< per piece, per vertex: its index in keys

  explicit KeyUnion(std::span<const KeyedPiece* const> pieces) {
    std::size_t total = 0;
    for (const KeyedPiece* p : pieces) total += p->keys.size();
    keys.reserve(total);
    for (const KeyedPiece* p : pieces) keys.insert(keys.end(), p->keys.begin(), p->keys.end());
    std::sort(keys.begin(), keys.end());
    keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
    for (const KeyedPiece* p : pieces) {
      // Both lists ascend: one walk places every vertex of the piece.
      std::vector<std::uint32_t> index(p->keys.size());
      std::size_t at = 0;
      for (std::size_t v = 0; v < index.size(); ++v) {
        while (keys[at] != p->keys[v]) ++at;
        index[v] = static_cast<std::uint32_t>(at);
      }
      of_piece.push_back(std::move(index));
    }
  }
};

}  // namespace citymesh
