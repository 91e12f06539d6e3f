// SPDX-License-Identifier: MIT
// All overlapping pairs between two sets of axis-aligned boxes (Embree's BVH-against-BVH
// rtcCollide behind this header): the candidate search of the change detection's exact
// triangle-tetrahedron tests.
#pragma once

#include <cstdint>
#include <functional>
#include <span>

#include "citymesh/core/vec.h"

namespace citymesh {

/// Closed axis-aligned box in a local float frame.
struct Box3f {
  Vec3f min, max;
};

struct BoxPair {
  std::uint32_t a = 0, b = 0;  ///< indices into the first and the second set
};

/// Calls `on_pairs` with batches of pairs (i, j) whose boxes a[i] and b[j] overlap, every such
/// pair exactly once, in no particular order and possibly from several threads at once (the
/// callback must be thread-safe). Boxes that merely touch may or may not be reported: pad them
/// when touching matters. Throws ProcessingError when Embree fails.
void collide_boxes(std::span<const Box3f> a, std::span<const Box3f> b,
                   const std::function<void(std::span<const BoxPair>)>& on_pairs);

}  // namespace citymesh
