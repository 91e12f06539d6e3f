// SPDX-License-Identifier: MIT
// Which boxes of a fixed set contain a point or meet a small box (a packed tree of boxes in
// Morton order behind this header): the candidate searches of the change detection.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "citymesh/core/vec.h"

namespace citymesh {

/// Closed axis-aligned box in a local float frame.
struct Box3f {
  Vec3f min, max;
  /// Whether the two closed boxes share a point (as Box3d::intersects).
  [[nodiscard]] bool intersects(const Box3f& b) const {
    return min.x <= b.max.x && b.min.x <= max.x && min.y <= b.max.y && b.min.y <= max.y && min.z <= b.max.z &&
           b.min.z <= max.z;
  }
};

/// A fixed set of boxes, indexed for containment and overlap queries.
class BoxTree {
 public:
  explicit BoxTree(std::vector<Box3f> boxes);
  ~BoxTree();
  BoxTree(const BoxTree&) = delete;
  BoxTree& operator=(const BoxTree&) = delete;

  /// Replaces `out` with the indices of the boxes containing p (closed boxes), in an order
  /// that depends on the boxes only. Thread-safe.
  void containing(const Vec3f& p, std::vector<std::uint32_t>& out) const;
  /// The most points containing_each() takes at once.
  static constexpr std::size_t kPacket = 8;
  /// containing() for each of `points` (at most kPacket, best close together): out[i] gets
  /// what containing(points[i], out[i]) gives, in the same order. One walk down the tree
  /// serves them all, so that neighbouring queries share the upper levels. Thread-safe.
  void containing_each(std::span<const Vec3f> points, std::span<std::vector<std::uint32_t>> out) const;
  /// containing() for `count` points (point_of(i) gives point i, best in an order that keeps
  /// neighbours together), kPacket at a time through containing_each(): calls on_hits(i, the
  /// boxes containing point i) for each, in order.
  template <class PointOf, class OnHits>
  void containing_in_packets(std::size_t count, PointOf point_of, OnHits on_hits) const {
    std::array<std::vector<std::uint32_t>, kPacket> hits;
    std::array<Vec3f, kPacket> packet{};
    for (std::size_t first = 0; first < count; first += kPacket) {
      const std::size_t n = std::min(kPacket, count - first);
      for (std::size_t k = 0; k < n; ++k) packet[k] = point_of(first + k);
      containing_each(std::span(packet).first(n), hits);
      for (std::size_t k = 0; k < n; ++k) on_hits(first + k, std::span<const std::uint32_t>(hits[k]));
    }
  }
  /// Replaces `out` with the indices of the boxes overlapping the closed box b, in an order
  /// that depends on the boxes only. Fast for small query boxes. Thread-safe.
  void overlapping(const Box3f& b, std::vector<std::uint32_t>& out) const;
  /// Every box index once, in the tree's storage order (along a space-filling curve): queries
  /// issued near the boxes in this order find their nodes in cache.
  [[nodiscard]] std::span<const std::uint32_t> storage_order() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace citymesh
