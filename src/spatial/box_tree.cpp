// SPDX-License-Identifier: MIT
// A packed box tree: boxes sorted along a Morton curve, then every kFanout consecutive nodes
// of a level bounded by one node of the level above. Built in linear time after one sort; the
// candidate sets of the change detection are coherent in space, so the packing is tight.
#include "citymesh/spatial/box_tree.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <iterator>
#include <limits>
#include <utility>

#include "citymesh/core/parallel.h"
#include "citymesh/core/radix_sort.h"

#ifdef __SSE2__
#include <emmintrin.h>  // four box tests at once: SSE2 is part of x86-64
#endif

namespace citymesh {

namespace {

/// Children per node. 8 boxes of 24 bytes are three cache lines, tested in one sweep.
constexpr std::size_t kFanout = 8;
/// Morton cells per axis (10 bits each make a 30-bit key that fits the pair sort).
constexpr float kCells = 1023.0f;

Box3f united(const Box3f& a, const Box3f& b) {
  return {{std::min(a.min.x, b.min.x), std::min(a.min.y, b.min.y), std::min(a.min.z, b.min.z)},
          {std::max(a.max.x, b.max.x), std::max(a.max.y, b.max.y), std::max(a.max.z, b.max.z)}};
}

/// Spreads the low 10 bits of v to every third bit.
std::uint32_t spread_bits(std::uint32_t v) {
  v &= 0x3ffu;
  v = (v | (v << 16)) & 0x030000ffu;
  v = (v | (v << 8)) & 0x0300f00fu;
  v = (v | (v << 4)) & 0x030c30c3u;
  v = (v | (v << 2)) & 0x09249249u;
  return v;
}

/// Where box centres fall on the Morton lattice spanning all the centres.
struct MortonFrame {
  Vec3f origin, scale;
  explicit MortonFrame(std::span<const Box3f> boxes) {
    Box3f all = {boxes[0].min + boxes[0].max, boxes[0].min + boxes[0].max};
    for (const Box3f& b : boxes) all = united(all, {b.min + b.max, b.min + b.max});  // twice the centres
    origin = all.min;
    const Vec3f extent = all.max - all.min;
    for (int k = 0; k < 3; ++k) scale[k] = extent[k] > 0 ? kCells / extent[k] : 0.0f;
  }
  [[nodiscard]] std::uint32_t code(const Box3f& b) const {
    const Vec3f c = b.min + b.max;
    std::uint32_t key = 0;
    for (int k = 0; k < 3; ++k) {
      const float cell = std::clamp((c[k] - origin[k]) * scale[k], 0.0f, kCells);
      key |= spread_bits(static_cast<std::uint32_t>(cell)) << k;
    }
    return key;
  }
};

/// kFanout boxes in columns, so that testing all of them against a query vectorises. Unused
/// slots hold an inverted box that meets nothing.
struct Node {
  alignas(32) float lo[3][kFanout];
  alignas(32) float hi[3][kFanout];

  Node() {
    for (int k = 0; k < 3; ++k) {
      std::fill(std::begin(lo[k]), std::end(lo[k]), std::numeric_limits<float>::infinity());
      std::fill(std::begin(hi[k]), std::end(hi[k]), -std::numeric_limits<float>::infinity());
    }
  }
  void set(std::size_t slot, const Box3f& b) {
    for (int k = 0; k < 3; ++k) {
      lo[k][slot] = b.min[k];
      hi[k][slot] = b.max[k];
    }
  }
  [[nodiscard]] Box3f bounds() const {
    Box3f b{{lo[0][0], lo[1][0], lo[2][0]}, {hi[0][0], hi[1][0], hi[2][0]}};
    for (std::size_t s = 1; s < kFanout; ++s)
      b = united(b, {{lo[0][s], lo[1][s], lo[2][s]}, {hi[0][s], hi[1][s], hi[2][s]}});
    return b;
  }
  /// Bit s set when slot s meets the query box.
  [[nodiscard]] unsigned meeting(const Box3f& q) const {
#ifdef __SSE2__
    unsigned mask = 0;
    for (std::size_t half = 0; half < kFanout; half += 4) {
      __m128 m = _mm_and_ps(_mm_cmple_ps(_mm_load_ps(lo[0] + half), _mm_set1_ps(q.max.x)),
                            _mm_cmple_ps(_mm_set1_ps(q.min.x), _mm_load_ps(hi[0] + half)));
      m = _mm_and_ps(m, _mm_cmple_ps(_mm_load_ps(lo[1] + half), _mm_set1_ps(q.max.y)));
      m = _mm_and_ps(m, _mm_cmple_ps(_mm_set1_ps(q.min.y), _mm_load_ps(hi[1] + half)));
      m = _mm_and_ps(m, _mm_cmple_ps(_mm_load_ps(lo[2] + half), _mm_set1_ps(q.max.z)));
      m = _mm_and_ps(m, _mm_cmple_ps(_mm_set1_ps(q.min.z), _mm_load_ps(hi[2] + half)));
      mask |= static_cast<unsigned>(_mm_movemask_ps(m)) << half;
    }
    return mask;
#else
    unsigned mask = 0;
    for (std::size_t s = 0; s < kFanout; ++s) {
      const bool m = (lo[0][s] <= q.max.x) & (q.min.x <= hi[0][s]) & (lo[1][s] <= q.max.y) & (q.min.y <= hi[1][s]) &
                     (lo[2][s] <= q.max.z) & (q.min.z <= hi[2][s]);
      mask |= static_cast<unsigned>(m) << s;
    }
    return mask;
#endif
  }
};

/// Nodes over consecutive groups of kFanout boxes, box i being box_at(i).
template <class BoxAt>
std::vector<Node> pack(std::size_t count, BoxAt box_at) {
  std::vector<Node> nodes((count + kFanout - 1) / kFanout);
  for (std::size_t i = 0; i < count; ++i) nodes[i / kFanout].set(i % kFanout, box_at(i));
  return nodes;
}

}  // namespace

struct BoxTree::Impl {
  /// levels[0] holds the boxes in curve order; levels[k + 1] bounds the nodes of levels[k];
  /// the last level is one node.
  std::vector<std::vector<Node>> levels;
  /// The caller's index of each box of levels[0], by slot.
  std::vector<std::uint32_t> original;
};

BoxTree::BoxTree(std::vector<Box3f> boxes) : impl_(std::make_unique<Impl>()) {
  if (boxes.empty()) return;
  const MortonFrame frame(boxes);
  std::vector<std::pair<std::uint32_t, std::uint32_t>> order(boxes.size());
  parallel_for_blocks(boxes.size(), 16384, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) order[i] = {frame.code(boxes[i]), static_cast<std::uint32_t>(i)};
  });
  // Ties broken by index (the pairs come in index order): the same tree on any thread count.
  stable_radix_sort_by_first(order);
  impl_->original.resize(boxes.size());
  for (std::size_t i = 0; i < order.size(); ++i) impl_->original[i] = order[i].second;
  std::vector<std::pair<std::uint32_t, std::uint32_t>>().swap(order);
  // Packed straight from the caller's boxes in curve order, which are then freed: a sorted
  // copy beside them was the peak of a city's seam pass (three arrays of every box at once).
  impl_->levels.push_back(pack(boxes.size(), [&](std::size_t i) { return boxes[impl_->original[i]]; }));
  std::vector<Box3f>().swap(boxes);
  while (impl_->levels.back().size() > 1) {
    const std::vector<Node>& below = impl_->levels.back();
    impl_->levels.push_back(pack(below.size(), [&](std::size_t i) { return below[i].bounds(); }));
  }
}

BoxTree::~BoxTree() = default;

std::span<const std::uint32_t> BoxTree::storage_order() const { return impl_->original; }

void BoxTree::containing(const Vec3f& p, std::vector<std::uint32_t>& out) const { overlapping({p, p}, out); }

void BoxTree::containing_each(std::span<const Vec3f> points, std::span<std::vector<std::uint32_t>> out) const {
  for (std::size_t i = 0; i < points.size(); ++i) out[i].clear();
  const auto& levels = impl_->levels;
  if (levels.empty() || points.empty()) return;
  Box3f all{points[0], points[0]};
  for (const Vec3f& p : points) all = united(all, {p, p});
  struct Visit {
    std::size_t level, node;
  };
  Visit stack[64 * kFanout];
  std::size_t top = 0;
  stack[top++] = {levels.size() - 1, 0};
  // The same walk as overlapping() with the points' box, so each point meets its leaves in
  // the order its own query would; only the leaves test the points one by one.
  while (top > 0) {
    const Visit v = stack[--top];
    const Node& node = levels[v.level][v.node];
    const unsigned mask = node.meeting(all);
    if (mask == 0) continue;
    if (v.level > 0) {
      for (unsigned m = mask; m != 0; m &= m - 1) {
        stack[top++] = {v.level - 1, v.node * kFanout + static_cast<std::size_t>(std::countr_zero(m))};
      }
      continue;
    }
    for (std::size_t i = 0; i < points.size(); ++i) {
      for (unsigned m = mask & node.meeting({points[i], points[i]}); m != 0; m &= m - 1) {
        out[i].push_back(impl_->original[v.node * kFanout + static_cast<std::size_t>(std::countr_zero(m))]);
      }
    }
  }
}

void BoxTree::overlapping(const Box3f& b, std::vector<std::uint32_t>& out) const {
  out.clear();
  const auto& levels = impl_->levels;
  if (levels.empty()) return;
  struct Visit {
    std::size_t level, node;
  };
  Visit stack[64 * kFanout];  // levels x fanout: far more than 2^32 boxes need
  std::size_t top = 0;
  stack[top++] = {levels.size() - 1, 0};
  while (top > 0) {
    const Visit v = stack[--top];
    for (unsigned mask = levels[v.level][v.node].meeting(b); mask != 0; mask &= mask - 1) {
      const std::size_t child = v.node * kFanout + static_cast<std::size_t>(std::countr_zero(mask));
      if (v.level == 0) {
        out.push_back(impl_->original[child]);
      } else {
        stack[top++] = {v.level - 1, child};
      }
    }
  }
}

}  // namespace citymesh
