// SPDX-License-Identifier: MIT
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cfloat>
#include <cmath>
#include <numeric>
#include <optional>
#include <span>
#include <vector>

#include "citymesh/core/error.h"
#include "citymesh/core/parallel.h"
#include "frames.h"

namespace citymesh::change_detail {

namespace {

/// Slabs whose joint box is asked of the mask before any of their own: most of an empty space
/// crosses open air, where no triangle asks, and one question then spares four slabs (on the
/// change benchmark 4 did better than 2, 8 or 16, and than groups within groups).
constexpr int kSlabsPerGroup = 4;

/// Marks the box of each of the n slabs: when the mask holds everything, no question is worth
/// asking (the group questions cost 12 % more there).
void mark_every_slab(const EmptySpaceSlabs& slabs, int n, OccupancyGrid& grid) {
  for (int k = 0; k < n; ++k) {
    const Box3f box = slabs.slab(k, n);
    grid.mark_box(box.min, box.max);
  }
}

/// Marks the box of each of the n slabs that touches `asked`, asking first about groups of
/// kSlabsPerGroup. Each cut's fraction k / n is divided once and used by the slabs on both
/// sides of it (the divisions were a fifth of the slabs' time).
void mark_asked_slabs(const EmptySpaceSlabs& slabs, int n, const VoxelMask& asked, OccupancyGrid& grid) {
  const double inverse = grid.inverse_voxel_size();
  const auto cut = [n](int k) { return double(k) / n; };
  double group_start = 0.0;
  for (int first = 0; first < n; first += kSlabsPerGroup) {
    const int last = std::min(n, first + kSlabsPerGroup);
    const double group_end = cut(last);
    const Box3f group = slabs.between(group_start, group_end);
    if (last - first > 1 && !asked.any_in(voxel_box(group.min, group.max, inverse))) {
      group_start = group_end;
      continue;
    }
    double s0 = group_start;
    for (int k = first; k < last; ++k) {
      const double s1 = k + 1 == last ? group_end : cut(k + 1);
      const Box3f box = slabs.between(s0, s1);
      const VoxelBox voxels = voxel_box(box.min, box.max, inverse);
      if (asked.any_in(voxels)) grid.mark_voxels(voxels);
      s0 = s1;
    }
    group_start = group_end;
  }
}

/// Marks the voxels the empty space of triangle g crosses, where `asked` holds them: the
/// tetrahedron is cut into slabs about one voxel long and each slab's box that touches
/// `asked` is marked whole.
void mark_empty_space(const TriangleFrames& f, std::size_t g, const VoxelMask& asked, OccupancyGrid& grid) {
  const TetrahedronCorners q = f.empty_space(g);
  const EmptySpaceSlabs slabs(q);
  const int n = slab_count(q, grid.voxel_size());
  if (asked.holds_everything()) {
    mark_every_slab(slabs, n, grid);
  } else {
    mark_asked_slabs(slabs, n, asked, grid);
  }
}

/// The dates of the acquisitions holding triangles, so that a pass absent from a tile makes
/// no work there (and the figures do not depend on passes elsewhere); empty when none does.
std::vector<TimePoint> held_dates(const TriangleFrames& f) {
  std::vector<TimePoint> out;
  for (std::size_t a = 0; a < f.acquisitions(); ++a) {
    if (f.holds(a)) out.push_back(f.dates[a]);
  }
  return out;
}

}  // namespace

VoxelMask asked_voxels(const TriangleFrames& f, double voxel_size) {
  // Every question is about the box of a triangle older than some acquisition's empty space.
  const std::vector<TimePoint> held = held_dates(f);
  if (held.empty()) return VoxelMask(std::span<const VoxelBox>{});
  const TimePoint newest = *std::max_element(held.begin(), held.end());
  const double inverse = OccupancyGrid::inverse_of(voxel_size);
  std::vector<VoxelBox> boxes;
  for (std::size_t a = 0; a < f.acquisitions(); ++a) {
    if (!(f.dates[a] < newest)) continue;
    for (std::size_t g = f.index.offsets[a]; g < f.index.offsets[a + 1]; ++g) {
      if (f.asks(g)) boxes.push_back(voxel_box(f.bounds(g).min, f.bounds(g).max, inverse));
    }
  }
  return VoxelMask(boxes);
}

std::vector<OccupancyGrid> build_empty_space_grids(const TriangleFrames& f, const ChangeParams& params,
                                                   const VoxelMask& asked, ChangeStats& stats) {
  // Only empty space newer than something is ever asked about: the oldest acquisitions'
  // grids stay empty. The others are marked in chunks of triangles, one grid each for an even
  // load whatever the acquisition sizes, then merged (a union: the order does not matter).
  if (f.dates.empty()) return {};
  const std::vector<TimePoint> held = held_dates(f);  // none: no triangle, no chunk below
  const TimePoint oldest = held.empty() ? f.dates.front() : *std::min_element(held.begin(), held.end());
  struct Chunk {
    std::size_t acquisition, begin, end;
  };
  constexpr std::size_t kChunk = 16384;
  std::vector<Chunk> chunks;
  for (std::size_t a = 0; a < f.acquisitions(); ++a) {
    if (!(oldest < f.dates[a])) continue;
    for (std::size_t g = f.index.offsets[a]; g < f.index.offsets[a + 1]; g += kChunk) {
      chunks.push_back({a, g, std::min(g + kChunk, f.index.offsets[a + 1])});
    }
  }
  std::vector<OccupancyGrid> chunk_grids;
  for (std::size_t c = 0; c < chunks.size(); ++c) chunk_grids.emplace_back(params.voxel_size);
  parallel_for_blocks(chunks.size(), 1, [&](std::size_t begin, std::size_t end) {
    for (std::size_t c = begin; c < end; ++c) {
      for (std::size_t g = chunks[c].begin; g < chunks[c].end; ++g) {
        if (f.empty_scale[g] > 0) mark_empty_space(f, g, asked, chunk_grids[c]);
      }
    }
  });
  std::vector<OccupancyGrid> grids;
  for (std::size_t a = 0; a < f.acquisitions(); ++a) grids.emplace_back(params.voxel_size);
  for (std::size_t c = 0; c < chunks.size(); ++c) grids[chunks[c].acquisition].merge(std::move(chunk_grids[c]));
  for (const OccupancyGrid& grid : grids) stats.marked_voxels += grid.marked_voxels();
  return grids;
}

namespace {

/// Triangles and their boxes, for the box collision.
struct BoxedTriangles {
  std::vector<std::uint32_t> ids;
  std::vector<Box3f> boxes;
  /// Holds every box (min above max while there is none).
  Box3f around{Vec3f{FLT_MAX, FLT_MAX, FLT_MAX}, Vec3f{-FLT_MAX, -FLT_MAX, -FLT_MAX}};

  void add(std::uint32_t id, const Box3f& box) {
    ids.push_back(id);
    boxes.push_back(box);
    around.min = {std::min(around.min.x, box.min.x), std::min(around.min.y, box.min.y),
                  std::min(around.min.z, box.min.z)};
    around.max = {std::max(around.max.x, box.max.x), std::max(around.max.y, box.max.y),
                  std::max(around.max.z, box.max.z)};
  }
};

/// The triangles that must be tested against acquisition j's empty space: older, not
/// consistent with j, and (with the pre-filter) near a voxel of j's grid.
BoxedTriangles conflict_candidates(const TriangleFrames& f, const PartnerBits& partners,
                                   std::span<const OccupancyGrid> grids, std::size_t j, const ChangeParams& params,
                                   ChangeStats& stats) {
  // In blocks on the pool, each with its own reader of the grid (consecutive triangles of a
  // scan fall in the same tree nodes), then put together in triangle order.
  struct Block {
    std::vector<std::uint32_t> ids;
    std::uint64_t candidates = 0, skipped = 0;
  };
  constexpr std::size_t kGrain = 16384;
  const std::size_t n = f.size();
  std::vector<Block> blocks((n + kGrain - 1) / kGrain);
  parallel_for_blocks(n, kGrain, [&](std::size_t begin, std::size_t end) {
    Block& block = blocks[begin / kGrain];
    std::optional<OccupancyGrid::Reader> reader;
    if (params.prefilter) reader.emplace(grids[j]);
    // The block's part of each older acquisition (newer ones have nothing to ask).
    for (std::size_t a = 0; a < f.acquisitions(); ++a) {
      if (!(f.dates[a] < f.dates[j])) continue;
      const std::size_t from = std::max(begin, f.index.offsets[a]), to = std::min(end, f.index.offsets[a + 1]);
      for (std::size_t g = from; g < to; ++g) {
        if (!f.asks(g) || partners.has(g, j)) continue;
        ++block.candidates;
        const Box3f& box = f.bounds(g);
        if (reader && !reader->any_in_box(box.min, box.max)) {
          ++block.skipped;
          continue;
        }
        block.ids.push_back(static_cast<std::uint32_t>(g));
      }
    }
  });
  BoxedTriangles out;
  for (const Block& block : blocks) {
    stats.conflict_candidates += block.candidates;
    stats.prefilter_skipped += block.skipped;
    for (const std::uint32_t g : block.ids) out.add(g, f.bounds(g));
  }
  return out;
}

/// A triangle lying wholly farther than this outside one face plane of a tetrahedron misses
/// it: far above the float rounding of the planes, so the quick rejection below is exact.
constexpr float kPlaneRejectMargin = 1e-3f;

/// The outward face planes of an empty space (unit normal, offset), for a quick rejection
/// before the exact test; a degenerate face gets a zero plane that rejects nothing.
struct FacePlanes {
  std::array<Vec3f, 4> normal;
  std::array<float, 4> offset;

  explicit FacePlanes(const TetrahedronCorners& q) {
    for (std::size_t i = 0; i < 4; ++i) {
      const Vec3d& a = q[(i + 1) % 4];
      Vec3d n = cross(q[(i + 2) % 4] - a, q[(i + 3) % 4] - a);
      const double len = norm(n);
      n = len > 0 ? n / len : Vec3d{0, 0, 0};
      if (dot(q[i] - a, n) > 0) n = n * -1.0;  // away from the opposite corner
      normal[i] = Vec3f(n);
      offset[i] = static_cast<float>(dot(n, a));
    }
  }

  /// True when the triangle lies wholly outside one face plane, with the margin.
  [[nodiscard]] bool misses(const std::array<Vec3f, 3>& t) const {
    for (std::size_t i = 0; i < 4; ++i) {
      const float limit = offset[i] + kPlaneRejectMargin;
      if (dot(normal[i], t[0]) > limit && dot(normal[i], t[1]) > limit && dot(normal[i], t[2]) > limit) return true;
    }
    return false;
  }
};

/// Acquisition j's triangles that have an empty space, with their face planes, and the boxes
/// the conflict search indexes: one per empty space, or one per slab of about
/// kConflictSlabLength when that pays (cut_if_it_pays()).
struct EmptySpaces {
  std::vector<std::uint32_t> ids;            ///< per empty space: its triangle
  std::vector<FacePlanes> planes;            ///< per empty space
  std::vector<std::size_t> first_slab;       ///< per empty space, and one past the last slab
  std::vector<Box3f> slab_boxes;             ///< empty (moved into the tree) when slab i is empty space i
  std::vector<std::uint32_t> space_of_slab;  ///< per slab, once cut (spaces_met reads it only then)

  /// Every empty space is one slab (not cut, or cut in no more than one).
  [[nodiscard]] bool slab_is_space() const { return first_slab.back() == ids.size(); }
};

/// Slabs of an empty space for the conflict search: a few metres long, so that the boxes stay
/// close to the empty space without multiplying them, and at most kMaxConflictSlabs, so that
/// the boxes of very long ones take bounded memory (see docs/change-detection.md).
constexpr double kConflictSlabLength = 2.0;
constexpr int kMaxConflictSlabs = 32;

/// Acquisition j's empty spaces, each one slab (its whole box).
EmptySpaces whole_empty_spaces(const TriangleFrames& f, std::size_t j) {
  EmptySpaces out;
  for (std::size_t g = f.index.offsets[j]; g < f.index.offsets[j + 1]; ++g) {
    if (f.empty_scale[g] > 0) out.ids.push_back(static_cast<std::uint32_t>(g));
  }
  const std::size_t n = out.ids.size();
  out.planes.resize(n, FacePlanes(TetrahedronCorners{}));
  out.slab_boxes.resize(n);
  parallel_for_blocks(n, 8192, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      const TetrahedronCorners q = f.empty_space(out.ids[i]);
      out.planes[i] = FacePlanes(q);
      out.slab_boxes[i] = EmptySpaceSlabs(q).slab(0, 1);
    }
  });
  out.first_slab.resize(n + 1);
  std::iota(out.first_slab.begin(), out.first_slab.end(), std::size_t{0});
  return out;
}

/// The slabs each empty space of `spaces` would be cut into.
std::vector<std::uint8_t> cut_slab_counts(const TriangleFrames& f, const EmptySpaces& spaces) {
  std::vector<std::uint8_t> counts(spaces.ids.size());
  parallel_for_blocks(counts.size(), 8192, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      counts[i] = static_cast<std::uint8_t>(
          std::min(slab_count(f.empty_space(spaces.ids[i]), kConflictSlabLength), kMaxConflictSlabs));
    }
  });
  return counts;
}

/// Cuts every empty space of `spaces` into its `cut_slabs` slabs.
void cut_into_slabs(const TriangleFrames& f, std::span<const std::uint8_t> cut_slabs, EmptySpaces& spaces) {
  const std::size_t n = spaces.ids.size();
  std::vector<std::size_t>& first_slab = spaces.first_slab;
  for (std::size_t i = 0; i < n; ++i) first_slab[i + 1] = first_slab[i] + cut_slabs[i];
  if (first_slab[n] > UINT32_MAX) {  // the box tree numbers its boxes in 32 bits
    throw ProcessingError(
        fmt::format("change detection: {} empty spaces in one acquisition cut into {} slabs, more "
                    "than 2^32; tile the acquisitions ([tiling])",
                    n, first_slab[n]));
  }
  spaces.slab_boxes.resize(first_slab[n]);
  spaces.space_of_slab.resize(first_slab[n]);
  parallel_for_blocks(n, 8192, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      const EmptySpaceSlabs slabs(f.empty_space(spaces.ids[i]));
      const int count = cut_slabs[i];
      for (int k = 0; k < count; ++k) {
        spaces.slab_boxes[first_slab[i] + k] = slabs.slab(k, count);
        spaces.space_of_slab[first_slab[i] + k] = static_cast<std::uint32_t>(i);
      }
    }
  });
}

/// What the conflict search indexes: the boxes of the slabs that meet `around`, the box
/// around every candidate, and which slab each is. The others can meet no candidate: a
/// tile's empty-space copies reach far beyond it, and their far slabs go.
struct IndexedSlabs {
  std::vector<std::uint32_t> slab;  ///< per box of the tree; empty when box k is slab k

  [[nodiscard]] std::uint32_t slab_of(std::uint32_t box) const { return slab.empty() ? box : slab[box]; }
};

/// The boxes of the slabs of `spaces` that meet `around`, for the tree. spaces_met reads the
/// slab boxes again only when empty spaces are cut into several slabs; otherwise they are
/// handed over.
std::vector<Box3f> indexed_boxes(EmptySpaces& spaces, const Box3f& around, IndexedSlabs& indexed) {
  std::vector<Box3f>& all = spaces.slab_boxes;
  indexed.slab.clear();
  const auto near = static_cast<std::size_t>(
      std::count_if(all.begin(), all.end(), [&](const Box3f& b) { return b.intersects(around); }));
  if (near == all.size()) return spaces.slab_is_space() ? std::move(all) : all;
  std::vector<Box3f> boxes;
  boxes.reserve(near);
  indexed.slab.reserve(near);
  for (std::size_t k = 0; k < all.size(); ++k) {
    if (!all[k].intersects(around)) continue;
    boxes.push_back(all[k]);
    indexed.slab.push_back(static_cast<std::uint32_t>(k));
  }
  if (spaces.slab_is_space()) std::vector<Box3f>().swap(all);
  return boxes;
}

/// Every how many candidates one is queried to decide whether to cut (a fixed stride: the
/// decision depends on the data only).
constexpr std::size_t kCutSampleStride = 64;
/// Cut when the candidates would meet more whole-space boxes than this many per slab the cut
/// tree would hold (a box met costs a few comparisons, a slab its share of building the
/// tree). Measured ratios: 18-130 on the real Ouster frames (tiled or not), where cutting
/// takes two thirds off the search; 4.3-6.7 on the simulated street untiled and at most 2.1
/// on the city's tiles, where it gains nothing or costs up to 9 %.
constexpr double kHitsPerSlabToCut = 10.0;

/// How many whole-space boxes all the candidates would meet, from a sample of them queried
/// against `whole`. A long empty space (a far return, or one seen at a slant) has a box far
/// larger than itself, which every candidate under it meets: on three real Ouster frames each
/// candidate met ~1 300 such boxes, one in ~5 000 of them worth an exact test. Slabs cover
/// the empty space, so the same pairs are tested, fewer are looked at; their price is a tree
/// 4-7 times larger, which only many hits repay (on the simulated city's tiles it made the
/// change step 8 % slower).
double expected_hits(const BoxTree& whole, const BoxedTriangles& candidates) {
  std::uint64_t hits_sampled = 0, sampled = 0;
  std::vector<std::uint32_t> hits;
  for (std::size_t i = 0; i < candidates.ids.size(); i += kCutSampleStride) {
    whole.overlapping(candidates.boxes[i], hits);
    hits_sampled += hits.size();
    ++sampled;
  }
  return double(hits_sampled) / double(std::max<std::uint64_t>(sampled, 1)) * double(candidates.ids.size());
}

/// Cuts acquisition j's empty spaces into slabs when `cut` says so or, measured, when the
/// expected hits pass kHitsPerSlabToCut per slab; returns whether it did. The slab counts
/// are worked out only when the hits pass that many per whole space (there are at least as
/// many slabs as spaces).
bool cut_if_it_pays(const TriangleFrames& f, const BoxTree& whole, const BoxedTriangles& candidates, SlabCut cut,
                    EmptySpaces& spaces) {
  if (cut == SlabCut::never) return false;
  const double hits = cut == SlabCut::measured ? expected_hits(whole, candidates) : 0.0;
  const auto pays = [&](std::size_t slabs) {
    return cut == SlabCut::always || hits > kHitsPerSlabToCut * double(slabs);
  };
  if (!pays(spaces.ids.size())) return false;
  const std::vector<std::uint8_t> counts = cut_slab_counts(f, spaces);
  const std::size_t slabs = std::accumulate(counts.begin(), counts.end(), std::size_t{0});
  if (slabs == spaces.ids.size() || !pays(slabs)) return false;
  cut_into_slabs(f, counts, spaces);
  return true;
}

/// The empty spaces whose slabs a query box met, each once: a slab stands for its empty
/// space unless the slab before it (nearer the viewpoint) meets the box too. The slabs of an
/// empty space that a box meets are consecutive (each bound of their boxes moves one way
/// along the empty space), so one slab of each is kept; were they not, an empty space would
/// only be tested twice, with the same answer.
void spaces_met(const EmptySpaces& spaces, const Box3f& query, std::span<const std::uint32_t> hits,
                std::vector<std::uint32_t>& out) {
  out.clear();
  if (spaces.slab_is_space()) {
    out.assign(hits.begin(), hits.end());
    return;
  }
  for (const std::uint32_t h : hits) {
    const std::uint32_t space = spaces.space_of_slab[h];
    if (h > spaces.first_slab[space] && spaces.slab_boxes[h - 1].intersects(query)) continue;
    out.push_back(space);
  }
}

}  // namespace

ConflictFlags find_conflicts(const TriangleFrames& f, const PartnerBits& partners, std::span<const OccupancyGrid> grids,
                             const ChangeParams& params, ChangeStats& stats, SlabCut cut) {
  ConflictFlags flags;
  flags.conflicting.assign(f.size(), 0);
  flags.refutes.assign(f.size(), 0);
  std::atomic<std::uint64_t> tests{0};
  for (std::size_t j = 0; j < f.acquisitions(); ++j) {
    if (!f.holds(j)) continue;  // no empty space: nothing to ask
    const BoxedTriangles older = conflict_candidates(f, partners, grids, j, params, stats);
    if (older.ids.empty()) continue;
    EmptySpaces spaces = whole_empty_spaces(f, j);
    IndexedSlabs indexed;
    std::optional<BoxTree> tree;
    tree.emplace(indexed_boxes(spaces, older.around, indexed));
    if (cut_if_it_pays(f, *tree, older, cut, spaces)) tree.emplace(indexed_boxes(spaces, older.around, indexed));
    // Every overlapping pair is tested (no early exit) so that `refutes` does not depend on
    // the thread count; the flags are only ever raised, so any order of raising gives the
    // same result.
    parallel_for_blocks(older.ids.size(), 256, [&](std::size_t begin, std::size_t end) {
      std::vector<std::uint32_t> hits, met;
      std::uint64_t tested = 0;
      for (std::size_t i = begin; i < end; ++i) {
        const std::uint32_t t = older.ids[i];
        const TriangleCorners corners = f.corners(t);  // once per candidate, not per test
        const bool raises = f.raises_refutes(t);
        // Without refutes to raise, one conflict settles the triangle.
        if (!raises && flags.conflicting[t] != 0) continue;
        tree->overlapping(older.boxes[i], hits);
        for (std::uint32_t& h : hits) h = indexed.slab_of(h);
        spaces_met(spaces, older.boxes[i], hits, met);
        for (const std::uint32_t h : met) {
          if (spaces.planes[h].misses(f.corner[t])) continue;
          const std::uint32_t u = spaces.ids[h];
          ++tested;
          if (triangle_intersects_tetrahedron(corners, f.empty_space(u))) {
            flags.conflicting[t] = 1;
            if (!raises) break;
            std::atomic_ref<std::uint8_t>(flags.refutes[u]).store(1, std::memory_order_relaxed);
          }
        }
      }
      tests.fetch_add(tested, std::memory_order_relaxed);
    });
  }
  stats.exact_tests = tests.load();
  return flags;
}

}  // namespace citymesh::change_detail
