// SPDX-License-Identifier: MIT
// Block stitching: the parts, the levels and the parts of a level in parallel. Cutting one
// part out and taking it back is part_cut.cpp's; keeping the parts between levels is the
// PartStore's (in memory in stitch_blocks_merged.cpp for stitch_in_blocks, in files for a
// tiled run: src/app/seam_parts.cpp).
#include "citymesh/mosaic/stitch_blocks.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <tuple>

#include "citymesh/core/checksum.h"
#include "citymesh/core/error.h"
#include "citymesh/core/interrupt.h"
#include "citymesh/core/log.h"
#include "citymesh/core/parallel.h"
#include "citymesh/core/process_memory.h"
#include "citymesh/core/progress.h"
#include "citymesh/core/radix_sort.h"
#include "citymesh/core/stopwatch.h"
#include "gap_fill.h"
#include "part_cut.h"
#include "part_sources.h"

namespace citymesh {

using mosaic_detail::Neighbour;
using mosaic_detail::PartCut;
using mosaic_detail::SourceRanks;

namespace {

constexpr int kLevels = kBlockStitchLevels;

/// Along one axis: the block holding a coordinate and, within `band` of a block side, that
/// side's grid line.
struct AxisCell {
  std::int64_t block = 0;
  std::optional<std::int64_t> line;
};

AxisCell axis_cell(double c, double origin, double size, double band) {
  const double f = (c - origin) / size;
  const auto block = static_cast<std::int64_t>(std::floor(f));
  const double u = (f - static_cast<double>(block)) * size;
  if (u < band) return {block, block};
  if (u > size - band) return {block, block + 1};
  return {block, std::nullopt};
}

/// The box a part has for the parts of `level`: stitched when its own level came before.
const Box3d& box_for_level(const BlockPart& part, int level) {
  return part.key.level < level ? part.stitched_box : part.box;
}

}  // namespace

namespace stitch_detail {

using KeyPair = std::pair<std::uint64_t, std::uint64_t>;  ///< an edge by its corners' keys, smaller first

/// An edge of a part used by one of its triangles only, and its length.
struct OnceEdge {
  KeyPair keys;
  double length = 0;
};

/// What the open boundary measure keeps of a part after reading it once.
struct PartEdges {
  std::vector<OnceEdge> once;    ///< in key order
  std::vector<KeyPair> meeting;  ///< sorted: the edges that may meet a part around
};

/// Finds the parts whose boxes (as a level sees them) meet a box: the boxes are filed under
/// every block cell they cover.
class PartFinder {
 public:
  PartFinder(std::span<const BlockPart> parts, const BlockStitchParams& blocks, int level)
      : parts_(parts), blocks_(blocks), level_(level) {
    for (std::size_t q = 0; q < parts.size(); ++q) {
      const Box3d& box = box_for_level(parts[q], level);
      if (box.empty()) continue;
      const Cells c = cells(box);
      for (std::int64_t i = c.i0; i <= c.i1; ++i) {
        for (std::int64_t j = c.j0; j <= c.j1; ++j) by_cell_[{i, j}].push_back(static_cast<std::uint32_t>(q));
      }
    }
  }

  /// The parts other than `self` whose boxes meet `reach`, in part order.
  [[nodiscard]] std::vector<std::uint32_t> meeting(const Box3d& reach, std::size_t self) const {
    std::vector<std::uint32_t> out;
    const Cells c = cells(reach);
    for (std::int64_t i = c.i0; i <= c.i1; ++i) {
      for (std::int64_t j = c.j0; j <= c.j1; ++j) {
        const auto it = by_cell_.find({i, j});
        if (it != by_cell_.end()) out.insert(out.end(), it->second.begin(), it->second.end());
      }
    }
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
    std::erase_if(out,
                  [&](std::uint32_t q) { return q == self || !box_for_level(parts_[q], level_).intersects(reach); });
    return out;
  }

 private:
  struct Cells {
    std::int64_t i0, i1, j0, j1;
  };
  [[nodiscard]] Cells cells(const Box3d& b) const {
    const auto cell = [&](double c, double origin) {
      return static_cast<std::int64_t>(std::floor((c - origin) / blocks_.size));
    };
    return {cell(b.min.x, blocks_.origin_x), cell(b.max.x, blocks_.origin_x), cell(b.min.y, blocks_.origin_y),
            cell(b.max.y, blocks_.origin_y)};
  }

  std::span<const BlockPart> parts_;
  const BlockStitchParams& blocks_;
  int level_;
  std::map<std::pair<std::int64_t, std::int64_t>, std::vector<std::uint32_t>> by_cell_;
};

}  // namespace stitch_detail

using stitch_detail::PartFinder;

namespace {

/// How far around a part its surroundings reach: the run's, or the farthest its steps look.
double part_context(const PartStitchRun& run) {
  return run.blocks.context > 0 ? run.blocks.context : block_context(run.params);
}

/// Stitches a part cut out with its surroundings; throws ProcessingError if stitching
/// changed them (they must come out first, unchanged, for the part to be taken back).
StitchStats stitch_cut(PartCut& cut, const StitchParams& params, std::span<const std::uint64_t> sizes) {
  const StitchStats stats =
      stitch(cut.merged, params,
             {.vertex_roles = cut.roles, .source_sizes = sizes, .first_own_triangle = cut.surroundings.size()});
  const std::vector<Triangle>& out = cut.merged.mesh.triangles;
  if (out.size() < cut.surroundings.size() ||
      !std::equal(cut.surroundings.begin(), cut.surroundings.end(), out.begin())) {
    throw ProcessingError("stitching block by block: a part's stitching changed the output around it");
  }
  return stats;
}

void add_counts(StitchStats& total, const StitchStats& s) {
  for (const auto count : kStitchCounts) total.*count += s.*count;
}

/// Adds a part's key to a digest, field by field (the struct has padding).
void add_part_key(BulkChecksum& sum, const BlockPartKey& k) {
  sum.add_value(std::int64_t{k.level});
  sum.add_value(k.x);
  sum.add_value(k.y);
}

/// The part index a new vertex's key names (kNewVertexKey | part << 32 | k).
std::uint64_t part_of_new_key(std::uint64_t key) { return (key & ~kNewVertexKey) >> 32; }

/// Keys whose new vertices name their part by its rank among `parts` (in key order) instead
/// of by its index in a run's list: what two runs agree on when parts appeared or went
/// elsewhere in the list. Ranks keep the keys' order (the list is in key order).
struct RelativeKeys {
  std::vector<std::uint64_t> keys;
  std::vector<BlockPartKey> parts;
};

RelativeKeys relative_keys(std::span<const std::uint64_t> keys, std::span<const BlockPart> parts) {
  std::vector<std::uint64_t> named;  // part indices, ascending
  for (const std::uint64_t k : keys) {
    if (k >= kNewVertexKey && (named.empty() || named.back() != part_of_new_key(k)))
      named.push_back(part_of_new_key(k));
  }
  std::sort(named.begin(), named.end());
  named.erase(std::unique(named.begin(), named.end()), named.end());
  RelativeKeys out;
  out.keys.reserve(keys.size());
  for (const std::uint64_t k : keys) {
    if (k < kNewVertexKey) {
      out.keys.push_back(k);
      continue;
    }
    const auto rank =
        static_cast<std::uint64_t>(std::lower_bound(named.begin(), named.end(), part_of_new_key(k)) - named.begin());
    out.keys.push_back(kNewVertexKey | rank << 32 | (k & 0xFFFFFFFFu));
  }
  for (const std::uint64_t q : named) {
    if (q >= parts.size()) throw ProcessingError("stitching block by block: a new vertex names no part of the run");
    out.parts.push_back(parts[q].key);
  }
  return out;
}

/// Renames the new vertices of `keys` (relative ones, as relative_keys made them, naming
/// `named`) after this run's parts (`parts`, in key order), in place; false when a part they
/// name is not in this run. Keys ascend, so the new vertices come last: only they change.
bool rename_for_this_run(std::vector<std::uint64_t>& keys, std::span<const BlockPartKey> named,
                         std::span<const BlockPart> parts) {
  std::vector<std::uint64_t> index;
  for (const BlockPartKey& key : named) {
    const auto it = std::lower_bound(parts.begin(), parts.end(), key,
                                     [](const BlockPart& part, const BlockPartKey& k) { return part.key < k; });
    if (it == parts.end() || it->key != key) return false;
    index.push_back(static_cast<std::uint64_t>(it - parts.begin()));
  }
  for (auto k = std::lower_bound(keys.begin(), keys.end(), kNewVertexKey); k != keys.end(); ++k) {
    const std::uint64_t rank = part_of_new_key(*k);
    if (rank >= index.size()) return false;
    *k = kNewVertexKey | index[rank] << 32 | (*k & 0xFFFFFFFFu);
  }
  return true;
}

/// A digest of `piece` with its new vertices named by their part's key (relative_keys). Keys
/// ascend, so the new vertices come last: only they are renamed.
std::uint64_t piece_digest_by_part_keys(const KeyedPiece& piece, std::span<const BlockPart> parts) {
  const auto first_new = std::lower_bound(piece.keys.begin(), piece.keys.end(), kNewVertexKey);
  const std::span<const std::uint64_t> head(piece.keys.begin(), first_new);
  const RelativeKeys relative = relative_keys(std::span<const std::uint64_t>(first_new, piece.keys.end()), parts);
  BulkChecksum sum;
  sum.add_value(keyed_piece_digest(piece, head, relative.keys));
  for (const BlockPartKey& k : relative.parts) add_part_key(sum, k);
  return sum.value();
}

/// The digest a PartCache finds part p by: everything its stitching reads besides the
/// settings. Clipping compares the sources' sizes only, so of those the order of the sources
/// present counts, not the sizes: a pass appended elsewhere changes every size, not this.
/// Parts are named by their keys, never by their index: an index is only the part's place in
/// this run's list, and stitching depends on the order of the parts only.
std::uint64_t part_digest(std::span<const BlockPart> parts, std::size_t p, const Vec3d& origin, double context,
                          const KeyedPiece& own, std::span<const std::uint32_t> around_parts,
                          std::span<const Neighbour> around, std::span<const std::uint64_t> source_sizes) {
  // Bumped when stitching a part reads something more (the cache also mixes in the build).
  constexpr std::uint64_t kFormat = 2;
  BulkChecksum sum;
  sum.add_value(kFormat);
  add_part_key(sum, parts[p].key);
  sum.add_value(origin);
  sum.add_value(context);
  sum.add_value(piece_digest_by_part_keys(own, parts));
  std::vector<std::int32_t> sources(own.source_acq.begin(), own.source_acq.end());
  for (std::size_t i = 0; i < around.size(); ++i) {
    add_part_key(sum, parts[around_parts[i]].key);
    sum.add_value(around[i].role);
    sum.add_value(piece_digest_by_part_keys(*around[i].piece, parts));
    sources.insert(sources.end(), around[i].piece->source_acq.begin(), around[i].piece->source_acq.end());
  }
  std::sort(sources.begin(), sources.end());
  sources.erase(std::unique(sources.begin(), sources.end()), sources.end());
  std::erase_if(sources, [&](std::int32_t a) { return a < 0 || static_cast<std::size_t>(a) >= source_sizes.size(); });
  // In the order clipping compares them: (size, index).
  std::sort(sources.begin(), sources.end(), [&](std::int32_t a, std::int32_t b) {
    return std::pair(source_sizes[static_cast<std::size_t>(a)], a) <
           std::pair(source_sizes[static_cast<std::size_t>(b)], b);
  });
  sum.add_array(std::span<const std::int32_t>(sources));
  return sum.value();
}

/// part_digest with each source named by its rank among those the part reads (`ranks`): a
/// part whose sources were renumbered (a pass delivered late elsewhere) keeps its digest.
/// When the sources are 0 to n-1 it is part_digest itself (no copy).
std::uint64_t ranked_part_digest(std::span<const BlockPart> parts, std::size_t p, const Vec3d& origin, double context,
                                 const KeyedPiece& own, std::span<const std::uint32_t> around_parts,
                                 std::span<const Neighbour> around, std::span<const std::uint64_t> source_sizes,
                                 const SourceRanks& ranks) {
  if (ranks.identity()) return part_digest(parts, p, origin, context, own, around_parts, around, source_sizes);
  std::vector<Neighbour> ranked;
  for (const Neighbour& n : around) ranked.push_back({std::make_shared<KeyedPiece>(*ranks.to_ranks(*n.piece)), n.role});
  // Clipping's precedence compares the sources by size, then index: by rank, the same order.
  std::vector<std::uint64_t> sizes;
  for (const std::uint32_t s : ranks.sources()) sizes.push_back(s < source_sizes.size() ? source_sizes[s] : 0);
  return part_digest(parts, p, origin, context, *ranks.to_ranks(own), around_parts, ranked, sizes);
}

/// Part p as `cache` kept it, its keys and sources those of this run (it was kept under the
/// ranks of the sources it read); nothing when it is not kept (or names a part or a rank this
/// run does not have).
std::optional<std::pair<KeyedPiece, PartOutcome>> find_kept(const PartCache& cache, std::span<const BlockPart> parts,
                                                            std::size_t p, std::uint64_t digest,
                                                            const SourceRanks& ranks) {
  auto kept = cache.find(parts[p].key, digest);
  if (!kept || !rename_for_this_run(kept->first.keys, kept->second.key_parts, parts)) return std::nullopt;
  if (!ranks.identity()) {
    std::optional<KeyedPiece> named = ranks.from_ranks(kept->first);
    if (!named) return std::nullopt;
    kept->first = std::move(*named);
  }
  kept->second.key_parts.clear();
  return kept;
}

/// Keeps stitched part p in `cache`, its new vertices named by their part's rank and its
/// sources by their rank among those it read (nothing kept when it holds another).
void keep_stitched(PartCache& cache, std::span<const BlockPart> parts, std::size_t p, const KeyedPiece& stitched,
                   PartOutcome outcome, const SourceRanks& ranks) {
  std::optional<KeyedPiece> kept = ranks.identity() ? stitched : ranks.to_ranks(stitched);
  if (!kept) return;
  RelativeKeys relative = relative_keys(kept->keys, parts);
  kept->keys = std::move(relative.keys);
  outcome.key_parts = std::move(relative.parts);
  cache.keep(parts[p].key, *kept, outcome);
}

/// Loads part p and the parts around it as level `level` sees them, stitches it (or takes it
/// from the run's cache) and saves it.
PartOutcome stitch_one(std::span<const BlockPart> parts, std::size_t p, int level, const PartFinder& finder,
                       PartStore& store, const PartStitchRun& run, double context) {
  const Box3d reach = parts[p].box.grown(context);
  std::vector<Neighbour> around;
  const std::vector<std::uint32_t> around_parts = finder.meeting(reach, p);
  for (const std::uint32_t q : around_parts) {
    const int other = parts[q].key.level;
    // A part of this level is stitched at the same time: where they touch, neither joins.
    const VertexRole role = other < level ? VertexRole::done : other == level ? VertexRole::held : VertexRole::later;
    around.push_back({store.load(q, other < level), role});
  }
  const std::shared_ptr<const KeyedPiece> own = store.load(p, false);
  const Vec3d origin = run.frame ? *run.frame : whole_metre_origin(parts[p].box.min);
  PartOutcome out;
  std::optional<SourceRanks> ranks;
  if (run.cache != nullptr) {
    ranks.emplace(*own, around);
    out.digest = ranked_part_digest(parts, p, origin, context, *own, around_parts, around, run.source_sizes, *ranks);
    if (auto kept = find_kept(*run.cache, parts, p, out.digest, *ranks)) {
      kept->second.digest = out.digest;
      kept->second.reused = true;
      store.save_stitched(p, std::move(kept->first));
      return kept->second;
    }
  }
  PartCut cut = mosaic_detail::cut_part(*own, around, reach, origin);
  around.clear();
  out.cut_triangles = cut.merged.mesh.triangle_count();
  out.stats = stitch_cut(cut, run.params, run.source_sizes);
  KeyedPiece stitched = mosaic_detail::stitched_piece(cut, p);
  out.box = stitched.box();
  if (run.cache != nullptr) keep_stitched(*run.cache, parts, p, stitched, out, *ranks);
  store.save_stitched(p, std::move(stitched));
  return out;
}

/// Stitches the parts of one level (run.run_level, or here), each part seeing the others of
/// its level as they were before the level (never as stitched); the outcomes are summed in
/// part order, so that the output is the same for any thread count, any number in flight and
/// any process doing each part.
void stitch_level(std::vector<BlockPart>& parts, int level, PartStore& store, const PartStitchRun& run,
                  BlockStitchStats& stats) {
  const LevelStitcher stitcher(parts, level, store, run);
  const std::uint64_t done_before = run.progress != nullptr ? run.progress->done() : 0;
  const std::uint64_t work_before = run.progress != nullptr ? run.progress->done_work() : 0;
  const std::vector<PartOutcome> outcomes = run.run_level ? run.run_level(stitcher) : stitch_level_here(stitcher);
  // The level's parts other processes stitched are counted once it ends.
  if (run.progress != nullptr) {
    std::uint64_t level_work = 0;
    // The level's inputs are let go only after it: their sizes are still there.
    for (const std::size_t p : stitcher.parts_of_level()) level_work += store.input_bytes(p);
    run.progress->advance(done_before + stitcher.size() - run.progress->done(),
                          work_before + level_work - run.progress->done_work());
  }
  if (outcomes.size() != stitcher.size())
    throw ProcessingError("stitching block by block: a level's outcomes are missing");
  for (std::size_t i = 0; i < outcomes.size(); ++i) {
    parts[stitcher.parts_of_level()[i]].stitched_box = outcomes[i].box;
    stats.largest_part = std::max(stats.largest_part, outcomes[i].cut_triangles);
    stats.reused_parts += outcomes[i].reused ? 1 : 0;
    stats.digests[stitcher.parts_of_level()[i]] = outcomes[i].digest;
    add_counts(stats.stitch, outcomes[i].stats);
  }
  stats.parts[static_cast<std::size_t>(level)] = stitcher.size();
}

using stitch_detail::KeyPair;

/// The edges of `piece` used by exactly one of its triangles, in key order (its corners'
/// indices, sorted, ascend with their keys), with their lengths.
std::vector<stitch_detail::OnceEdge> edges_used_once(const KeyedPiece& piece) {
  using Edge = std::pair<std::uint32_t, std::uint32_t>;  // the piece's vertices, smaller first
  std::vector<Edge> edges;
  edges.reserve(3 * piece.triangle_count());
  for (const Triangle& tri : piece.triangles) {
    for (int k = 0; k < 3; ++k) edges.push_back(std::minmax(tri[k], tri[(k + 1) % 3]));
  }
  radix_sort_pairs(edges);
  std::vector<stitch_detail::OnceEdge> once;
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t end = i + 1;
    while (end < edges.size() && edges[end] == edges[i]) ++end;
    if (end == i + 1) {
      const auto [a, b] = edges[i];
      once.push_back({{piece.keys[a], piece.keys[b]}, norm(piece.positions[a] - piece.positions[b])});
    }
    i = end;
  }
  return once;
}

/// The edges (sorted, each once) of the triangles of `piece` whose box meets one of `boxes`:
/// the only ones another part whose box that is can share. A triangle sharing an edge with
/// another part's triangle holds two of its corners, so its box meets that part's box.
std::vector<KeyPair> edges_meeting(const KeyedPiece& piece, std::span<const Box3d> boxes) {
  std::vector<KeyPair> out;
  for (std::size_t t = 0; t < piece.triangle_count(); ++t) {
    const Box3d box = piece.box(t);
    if (std::none_of(boxes.begin(), boxes.end(), [&](const Box3d& b) { return b.intersects(box); })) continue;
    const Triangle& tri = piece.triangles[t];
    for (int k = 0; k < 3; ++k) out.push_back(std::minmax(piece.keys[tri[k]], piece.keys[tri[(k + 1) % 3]]));
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

}  // namespace

BoundaryMeasurer::BoundaryMeasurer(std::span<const BlockPart> parts, const PartStore& store, bool stitched,
                                   const BlockStitchParams& blocks)
    : parts_(parts),
      store_(store),
      stitched_(stitched),
      // As the last level sees them (all stitched) or as the first does (none).
      view_(stitched ? kLevels : -1),
      finder_(std::make_unique<PartFinder>(parts, blocks, view_)),
      kept_(std::make_unique<Kept>(parts.size())) {}

BoundaryMeasurer::~BoundaryMeasurer() = default;

struct BoundaryMeasurer::Kept {
  explicit Kept(std::size_t parts) : read(parts), edges(parts) {}
  std::vector<std::once_flag> read;
  std::vector<stitch_detail::PartEdges> edges;
};

const stitch_detail::PartEdges& BoundaryMeasurer::edges_of(std::size_t q) const {
  std::call_once(kept_->read[q], [&] {
    const std::shared_ptr<const KeyedPiece> piece = store_.load(q, stitched_);
    std::vector<Box3d> around;
    for (const std::uint32_t r : finder_->meeting(box_for_level(parts_[q], view_), q)) {
      around.push_back(box_for_level(parts_[r], view_));
    }
    kept_->edges[q] = {edges_used_once(*piece), edges_meeting(*piece, around)};
  });
  return kept_->edges[q];
}

/// Part p's edges used once by its own triangles and by none of the parts around it (every
/// triangle sharing an edge with p's is in one of them), summed in key order.
double BoundaryMeasurer::measure(std::size_t p) const {
  const Box3d& box = box_for_level(parts_[p], view_);
  if (box.empty()) return 0.0;
  std::vector<const stitch_detail::PartEdges*> around;
  for (const std::uint32_t q : finder_->meeting(box, p)) around.push_back(&edges_of(q));
  double length = 0;
  for (const stitch_detail::OnceEdge& e : edges_of(p).once) {
    const bool shared = std::any_of(around.begin(), around.end(), [&](const stitch_detail::PartEdges* q) {
      return std::binary_search(q->meeting.begin(), q->meeting.end(), e.keys);
    });
    if (!shared) length += e.length;
  }
  return length;
}

double parts_open_boundary(std::span<const BlockPart> parts, const PartStore& store, bool stitched,
                           const BlockStitchParams& blocks, const MeasureParts& measure_parts) {
  const BoundaryMeasurer measurer(parts, store, stitched, blocks);
  std::vector<double> lengths;
  if (measure_parts) {
    lengths = measure_parts(measurer);
    if (lengths.size() != parts.size()) throw ProcessingError("open boundary by parts: lengths are missing");
  } else {
    lengths.assign(parts.size(), 0.0);
    parallel_for_blocks(parts.size(), 1, [&](std::size_t begin, std::size_t end) {
      for (std::size_t p = begin; p < end; ++p) lengths[p] = measurer.measure(p);
    });
  }
  double total = 0;
  for (const double l : lengths) total += l;  // in part order: the same sum on any thread count
  return total;
}

LevelStitcher::LevelStitcher(std::span<const BlockPart> parts, int level, PartStore& store, const PartStitchRun& run)
    : parts_(parts),
      level_(level),
      store_(store),
      run_(run),
      context_(part_context(run)),
      finder_(std::make_unique<PartFinder>(parts, run.blocks, level)) {
  for (std::size_t i = 0; i < parts.size(); ++i) {
    if (parts[i].key.level == level) of_level_.push_back(i);
  }
}

LevelStitcher::~LevelStitcher() = default;

PartOutcome LevelStitcher::stitch(std::size_t i) const {
  PartOutcome out = stitch_one(parts_, of_level_.at(i), level_, *finder_, store_, run_, context_);
  if (run_.progress != nullptr) run_.progress->advance(1, store_.input_bytes(of_level_.at(i)));
  return out;
}

std::vector<PartOutcome> stitch_level_here(const LevelStitcher& level) {
  std::vector<PartOutcome> outcomes(level.size());
  // Isolated workers: a thread waiting inside one part's parallel loops never starts another
  // part, so the parts in flight stay at most one per thread. One part's error stops the
  // others after their current part.
  const unsigned workers = std::min(available_threads(), kMaxSeamPartsInFlight);
  parallel_jobs(level.size(), workers, [&](std::size_t i) {
    throw_if_interrupted("the seam pass");
    outcomes[i] = level.stitch(i);
  });
  return outcomes;
}

std::string BlockPartKey::name() const { return fmt::format("{}_{}_{}", level, x, y); }

BlockPartKey block_part_of(const Vec3d& centroid, const BlockStitchParams& p) {
  const AxisCell x = axis_cell(centroid.x, p.origin_x, p.size, p.band);
  const AxisCell y = axis_cell(centroid.y, p.origin_y, p.size, p.band);
  if (x.line && y.line) return {3, *x.line, *y.line};
  if (x.line) return {1, *x.line, y.block};
  if (y.line) return {2, x.block, *y.line};
  return {0, x.block, y.block};
}

void check_block_layout(const BlockStitchParams& p, double context) {
  const bool finite = std::isfinite(p.origin_x) && std::isfinite(p.origin_y) && std::isfinite(p.size) &&
                      std::isfinite(p.band) && std::isfinite(context);
  if (!finite || !(p.size > 0) || !(p.band >= context) || !(4 * p.band < p.size)) {
    throw std::invalid_argument(fmt::format(
        "stitching block by block: blocks of {} m with bands of {} m and a context of {} m (the band must be at "
        "least the context and under a quarter of the block)",
        p.size, p.band, context));
  }
}

double block_context(const StitchParams& params) {
  const double farthest =
      std::max({params.snap, params.reach, params.clip, 0.5 * mosaic_detail::kGapPerimeterInWidths * params.gap});
  return 1.25 * farthest;  // a margin: what is looked for near a vertex may lie a little farther
}

BlockStitchStats stitch_parts(std::vector<BlockPart>& parts, PartStore& store, const PartStitchRun& run) {
  check_block_layout(run.blocks, part_context(run));
  if (!std::is_sorted(parts.begin(), parts.end(),
                      [](const BlockPart& a, const BlockPart& b) { return a.key < b.key; })) {
    throw ProcessingError("stitching block by block: the parts are not in key order");
  }
  BlockStitchStats stats;
  stats.digests.assign(parts.size(), 0);
  const Stopwatch clock;
  for (int level = 0; level < kLevels; ++level) {
    stitch_level(parts, level, store, run, stats);
    // Later levels see this level's parts stitched only.
    for (std::size_t p = 0; p < parts.size(); ++p) {
      if (parts[p].key.level == level) store.release_input(p);
    }
    log::debug("stitch by blocks: level {} ({} parts) at {:.2f} s, {}", level,
               stats.parts[static_cast<std::size_t>(level)], clock.seconds(), memory_note());
  }
  return stats;
}

}  // namespace citymesh
