// SPDX-License-Identifier: MIT
// Stitching an output block by block: each part of it once, with what lies around it as
// frozen surroundings (StitchSurroundings), so that a part needs memory of its own size and
// the parts of one level run in parallel. The parts live in a PartStore between levels: in
// memory (stitch_in_blocks) or in files (a tiled run's bounded final pass).
#pragma once

#include <array>
#include <compare>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "citymesh/core/keyed_piece.h"
#include "citymesh/mosaic/stitch.h"

namespace citymesh {

/// A square grid of blocks over the output, in the frame of the positions it is given, and
/// the bands along the block sides.
struct BlockStitchParams {
  double origin_x = 0, origin_y = 0;  ///< metres: a corner of the grid
  double size = 50;                   ///< metres: a block's side
  /// metres either side of each block side: stitched after the block interiors, with them as
  /// output stitched before. At least `context`, so that the parts of one level never reach
  /// each other; less than a quarter of `size`.
  double band = 2;
  /// metres around a part from which its surroundings are taken; 0: the farthest the
  /// stitching steps of the params look (block_context()).
  double context = 0;
};

struct BlockStitchStats {
  StitchStats stitch;  ///< the whole output's open boundary before and after; counts summed over the parts
  /// per level: block interiors, bands along x = const, bands along y = const, corner squares
  std::array<std::size_t, 4> parts{};
  std::size_t largest_part = 0;        ///< triangles of the largest part with its surroundings
  std::size_t reused_parts = 0;        ///< taken from the run's PartCache instead of stitched
  std::vector<std::uint64_t> digests;  ///< per part, with a PartCache: PartOutcome::digest
};

/// The farthest any step of `params` looks from a vertex (snapping, joining, clipping, the
/// gaps' perimeter), with a margin: what a part's surroundings must hold.
double block_context(const StitchParams& params);

/// Stitches `mesh` as stitch() does, part by part in four levels. First every block's
/// interior, with the bands along its sides as surroundings stitched later; then each band
/// without its ends, those along x = const before those along y = const, with what was
/// stitched before as done and the rest later; then the corner squares, with everything
/// else done. Each triangle belongs to the part holding its centroid. A part sees only the
/// triangles within the context of it, the parts of its own level as they were before the
/// level; the parts of a level run in parallel and the output (parts in level and grid order,
/// the mesh's vertices first and in place, new ones after) is the same whatever the thread
/// count. `blocks` is in the mesh's frame. Throws std::invalid_argument on a layout that
/// breaks the rules above.
BlockStitchStats stitch_in_blocks(MergedMesh& mesh, const StitchParams& params, const BlockStitchParams& blocks);

// ----- The parts, and stitching them wherever they are kept ------------------------------

/// Which part a triangle belongs to. Level 0: a block interior (x, y: the block). Level 1: a
/// band along the grid line x, without its ends (y: the block row). Level 2: the same along
/// the grid line y (x: the block column). Level 3: the corner square at grid point (x, y).
/// The parts of one level lie apart: the bands along x are held apart by the corner squares,
/// and so on (the two kinds of band touch at the corner squares' inner corners).
struct BlockPartKey {
  int level = 0;
  std::int64_t x = 0, y = 0;
  friend auto operator<=>(const BlockPartKey&, const BlockPartKey&) = default;
  /// "<level>_<x>_<y>": a file name.
  [[nodiscard]] std::string name() const;
};

/// The part of a triangle whose centroid is `centroid` (same frame as `blocks`).
BlockPartKey block_part_of(const Vec3d& centroid, const BlockStitchParams& blocks);

/// Throws std::invalid_argument when `blocks` breaks the rules of BlockStitchParams for
/// surroundings of `context` metres.
void check_block_layout(const BlockStitchParams& blocks, double context);

/// The levels of stitch_parts(): block interiors, bands along x, bands along y, corners.
inline constexpr int kBlockStitchLevels = 4;

/// Keys of the vertices stitching makes: kNewVertexKey | part << 32 | k for the k-th vertex
/// part `part` (its index in the run's part list) made. Other keys are the caller's own, below.
inline constexpr std::uint64_t kNewVertexKey = std::uint64_t{1} << 63;

/// Where block stitching keeps the parts between levels.
class PartStore {
 public:
  virtual ~PartStore() = default;
  /// Part `part` (its index in the run's list) as it was before stitching, or once stitched
  /// (only after save_stitched). Called from several threads at once.
  [[nodiscard]] virtual std::shared_ptr<const KeyedPiece> load(std::size_t part, bool stitched) const = 0;
  /// Keeps the stitched triangles of part `part`: once per part, from several threads at once
  /// (never for the same part).
  virtual void save_stitched(std::size_t part, KeyedPiece stitched) = 0;
  /// Part `part` as it was before stitching is not read again (its level is done): the store
  /// may let it go.
  virtual void release_input(std::size_t /*part*/) {}
  /// The size of part `part`'s input in bytes, while it is kept (what stitching it costs,
  /// roughly); 0 when the store does not tell.
  [[nodiscard]] virtual std::uint64_t input_bytes(std::size_t /*part*/) const { return 0; }
};

/// A part of a run: its key and the box of its triangles before and after stitching.
struct BlockPart {
  BlockPartKey key;
  Box3d box, stitched_box;
};

class LevelStitcher;
class StageProgress;

namespace stitch_detail {
class PartFinder;  ///< which parts' boxes (as a level sees them) meet a box
struct PartEdges;  ///< what the open boundary measure keeps of a part
}  // namespace stitch_detail

/// What stitching one part gives back.
struct PartOutcome {
  StitchStats stats;
  Box3d box;                      ///< of the stitched part's triangles
  std::size_t cut_triangles = 0;  ///< the part with its surroundings, as stitched
  /// With a PartCache: the digest of everything the part's stitching read (part_digest), and
  /// whether the stitched part came from the cache.
  std::uint64_t digest = 0;
  bool reused = false;
  /// With a PartCache: the parts whose new vertices the kept piece holds, in key order; the
  /// kept piece names them by their rank here instead of by their index in the run's list
  /// (kNewVertexKey | rank << 32 | k), so that a part is reused when parts appear or go
  /// before it in the list.
  std::vector<BlockPartKey> key_parts;
};

/// Stitched parts kept from earlier runs, found by a digest of everything a part's stitching
/// reads (the part, the parts around it as its level sees them, the order of precedence of
/// the sources among them, its key and frame; new vertices named by the key of the part that
/// made them, not by its index): a run that changed only some parts
/// (an acquisition appended over one district) stitches again only the parts whose inputs
/// changed, and gets the bytes of stitching them all. The implementation adds the settings.
class PartCache {
 public:
  virtual ~PartCache() = default;
  /// The part `key` stitched from inputs of digest `digest`, with its outcome, if kept (a
  /// damaged entry is not found). Called from several threads at once.
  [[nodiscard]] virtual std::optional<std::pair<KeyedPiece, PartOutcome>> find(const BlockPartKey& key,
                                                                               std::uint64_t digest) const = 0;
  /// Keeps part `key` stitched from inputs of digest `outcome.digest`. Called from several
  /// threads at once, never for the same part.
  virtual void keep(const BlockPartKey& key, const KeyedPiece& stitched, const PartOutcome& outcome) = 0;
};

struct PartStitchRun {
  StitchParams params;
  BlockStitchParams blocks;  ///< in the frame of the pieces' positions, context set
  /// Per source: its triangles in the whole output (clipping's precedence).
  std::vector<std::uint64_t> source_sizes;
  /// The frame every part is stitched in; unset: each part's own, the lowest corner of its
  /// box in whole metres (floats relative to it keep their precision anywhere in a city).
  std::optional<Vec3d> frame;
  /// Stitches every part of one level (stitcher.stitch(i) for each i < stitcher.size(), on
  /// any thread of any process sharing the store) and returns their outcomes in that order.
  /// Unset: on this process's threads (stitch_level_here). A tiled MPI run hands the parts out
  /// to every rank.
  std::function<std::vector<PartOutcome>(const LevelStitcher&)> run_level;
  /// Where stitched parts are looked up before stitching and kept after; null: none.
  PartCache* cache = nullptr;
  /// Told of each part stitched by this process, and of a level's other parts when the level
  /// ends (run_level may hand them to other processes), each weighed by its input's bytes
  /// (PartStore::input_bytes); null: none.
  StageProgress* progress = nullptr;
};

/// The parts of one level of stitch_parts(), each stitched on its own: loaded with the parts
/// around it as the level sees them, stitched, and saved in the store. Parts of one level
/// never meet, so any number can be stitched at once, in any order, by any process whose
/// store reads and writes the same parts.
class LevelStitcher {
 public:
  /// `parts` as stitch_parts() has them when the level starts (the stitched boxes of earlier
  /// levels set); they, the store and the run must outlive this.
  LevelStitcher(std::span<const BlockPart> parts, int level, PartStore& store, const PartStitchRun& run);
  ~LevelStitcher();
  LevelStitcher(const LevelStitcher&) = delete;
  LevelStitcher& operator=(const LevelStitcher&) = delete;

  [[nodiscard]] int level() const { return level_; }
  /// Every part of the run, as this level sees them.
  [[nodiscard]] std::span<const BlockPart> parts() const { return parts_; }
  /// The parts of this level, as indices into the run's parts, in part order.
  [[nodiscard]] std::span<const std::size_t> parts_of_level() const { return of_level_; }
  [[nodiscard]] std::size_t size() const { return of_level_.size(); }
  /// Stitches the i-th part of the level and saves it. Thread-safe for different i.
  [[nodiscard]] PartOutcome stitch(std::size_t i) const;

 private:
  std::span<const BlockPart> parts_;
  int level_;
  PartStore& store_;
  const PartStitchRun& run_;
  double context_;
  std::vector<std::size_t> of_level_;
  std::unique_ptr<stitch_detail::PartFinder> finder_;
};

/// At most this many parts are cut out and stitched (or measured) at a time by one process,
/// whatever its threads: their memory is what a level adds (the city's largest part with its
/// surroundings: ~30 MB).
inline constexpr unsigned kMaxSeamPartsInFlight = 16;

/// Runs every part of the level on this process's threads, a few at a time (the default of
/// PartStitchRun::run_level).
std::vector<PartOutcome> stitch_level_here(const LevelStitcher& level);

/// Stitches every part of `parts` (sorted by key, boxes set) level by level as
/// stitch_in_blocks describes, reading them from `store` and saving each one stitched there;
/// sets their stitched boxes. The open boundary figures are left to the caller.
BlockStitchStats stitch_parts(std::vector<BlockPart>& parts, PartStore& store, const PartStitchRun& run);

/// The open boundary of each part of an output, before stitching or once stitched: the length
/// of its triangles' edges used by exactly one triangle, counted with the parts around it.
/// Any number at once, on any process whose store reads the same parts. Each part is read
/// once: what the measures need of it (its edges used once, and the edges of its triangles
/// that meet the box of a part around it) is kept until the measurer goes.
class BoundaryMeasurer {
 public:
  /// `parts`, `store` and `blocks` (the grid of the parts) must outlive this.
  BoundaryMeasurer(std::span<const BlockPart> parts, const PartStore& store, bool stitched,
                   const BlockStitchParams& blocks);
  ~BoundaryMeasurer();
  BoundaryMeasurer(const BoundaryMeasurer&) = delete;
  BoundaryMeasurer& operator=(const BoundaryMeasurer&) = delete;

  [[nodiscard]] std::size_t size() const { return parts_.size(); }
  [[nodiscard]] bool stitched() const { return stitched_; }
  [[nodiscard]] std::span<const BlockPart> parts() const { return parts_; }
  /// Part p's open boundary, metres. Thread-safe.
  [[nodiscard]] double measure(std::size_t p) const;

 private:
  std::span<const BlockPart> parts_;
  const PartStore& store_;
  bool stitched_;
  int view_;  ///< the level whose view of the parts' boxes is measured
  std::unique_ptr<stitch_detail::PartFinder> finder_;
  struct Kept;
  std::unique_ptr<Kept> kept_;  ///< per part, read at its first use

  /// Part q's edges, read at the first call (thread-safe).
  [[nodiscard]] const stitch_detail::PartEdges& edges_of(std::size_t q) const;
};

/// Measures every part (measurer.measure(p) for each p, anywhere) and returns the lengths in
/// part order. Unset: on this process's threads.
using MeasureParts = std::function<std::vector<double>(const BoundaryMeasurer&)>;

/// The open boundary of the whole output the parts hold, before stitching or once stitched:
/// the parts' lengths (BoundaryMeasurer) summed in part order, so the same on any thread
/// count (`blocks`: the grid of the parts).
double parts_open_boundary(std::span<const BlockPart> parts, const PartStore& store, bool stitched,
                           const BlockStitchParams& blocks, const MeasureParts& measure_parts = {});

}  // namespace citymesh
