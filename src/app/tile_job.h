// SPDX-License-Identifier: MIT
// One tile of a tiled run: change detection and the mosaic on the tile with its halo, the
// owner's decisions written to <work>/results/<tile>.bin (and read back on resume).
#pragma once

#include <compare>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <span>
#include <vector>

#include "citymesh/change/detect.h"
#include "citymesh/config/config.h"
#include "citymesh/tiler/tiler.h"
#include "label_pairs.h"

namespace citymesh::app {

/// What the change step and the mosaic decided for one owned triangle.
struct OwnedLabel {
  std::uint32_t acquisition = 0;
  std::uint32_t index = 0;  ///< triangle index in the acquisition
  TriangleState state = TriangleState::single;
  std::uint8_t kept = 0, sustainable = 0, refutes = 0, selected = 0;
  std::uint8_t notes = 0;  ///< the mosaic's MosaicNote bits
  std::uint8_t pad[2]{};
  std::int64_t first_ms = 0, last_ms = 0;  ///< first_seen, last_seen (Unix milliseconds)
};
static_assert(sizeof(OwnedLabel) == 32);

/// The order of labels in a tile result: by acquisition, then triangle index.
bool by_triangle(const OwnedLabel& x, const OwnedLabel& y);

/// The mosaic's decisions on triangles that earlier-phase neighbours own: the tile keeps
/// them for its halo copies of those triangles (see process_tile).
class SettledSelection {
 public:
  /// Adds a neighbour's labels, sorted by triangle as a tile result holds them; neighbours own
  /// disjoint triangles.
  void add(std::span<const OwnedLabel> labels);
  /// Whether a neighbour selected triangle `index` of `acquisition`; nothing when no
  /// neighbour added has decided it.
  [[nodiscard]] std::optional<bool> selected(std::uint32_t acquisition, std::uint32_t index) const;
  [[nodiscard]] std::size_t size() const { return keys_.size(); }

 private:
  /// acquisition << 33 | index << 1 | selected, sorted: an eighth of the labels' bytes, and
  /// each neighbour's run merged in linear time instead of sorting them all.
  std::vector<std::uint64_t> keys_;
};

/// A triangle of another tile (a halo or empty-space copy here) whose empty space an owned
/// triangle of this tile conflicts with: the assembly raises its `refutes` label.
struct RefutedCopy {
  std::uint32_t acquisition = 0, index = 0;
  friend auto operator<=>(const RefutedCopy&, const RefutedCopy&) = default;
};

struct TileResult {
  TileKey key;
  std::vector<OwnedLabel> labels;  ///< every owned triangle, by (acquisition, index)
  /// The consistent pairs with an owned member, sorted, then the pairs of layers of one pass
  /// with one, sorted (a reader tells the two apart by their acquisitions).
  LabelPairList pairs;
  /// Copies refuted by this tile's owned triangles, sorted. A conflict between an owned triangle
  /// T and the empty space of a triangle U is found in T's owner tile (U's empty space meets T,
  /// so it crosses that tile or its halo, and the tiler copied U there): every tile counts the
  /// conflicts of its owned triangles only, and U's `refutes` is the union over the tiles.
  std::vector<RefutedCopy> refuted;
  /// Per acquisition, the selected owned triangles with their vertices (tile frame).
  std::vector<TilePiece> selected;
  /// The acquisitions the tile held (TileContents::passes) in the numbering of the ids above:
  /// what restamp_tile_result maps from when a pass delivered late renumbers them.
  std::vector<std::uint32_t> passes;
  double seconds_read = 0, seconds_detect = 0, seconds_mosaic = 0;
  std::uint64_t triangles_in_tile = 0;  ///< owned, halo and empty space
  ChangeStats change;                   ///< the change step's figures on the whole tile
  /// What the earlier-phase neighbours' decisions said of the halo (tile_settled_fingerprint):
  /// with the tile's own inputs, all the result depends on.
  std::uint64_t settled_fingerprint = 0;
};

/// The phase of a tile: tiles of one phase never touch (no shared border or corner), so they
/// run in parallel; tiles of later phases see the decisions of their earlier neighbours.
int tile_phase(TileKey key);
inline constexpr int kTilePhases = 4;

/// Reads the tile, runs detect_changes on all of it (owned triangles labelled, halo ones as
/// context, empty-space copies giving only their empty space), then the mosaic (energy or
/// update model) on its owned and halo triangles, and keeps the owned triangles' outcome and
/// the copies they refute. `settled`: the labels of neighbouring tiles of earlier phases
/// (sorted by acquisition and index); their halo triangles keep the owner's choice (selected
/// ones are forced into the energy mosaic, the others are no candidates), so both sides of a
/// tile border agree.
TileResult process_tile(const TileStore& store, TileKey key, const Config& config, const SettledSelection& settled);

/// A digest of what `settled` says of tile `key`'s halo triangles (reads the tile): equal
/// for two selections, the tile job gives the same result from both.
std::uint64_t tile_settled_fingerprint(const TileStore& store, TileKey key, const SettledSelection& settled);

/// The digests a result is written under (tile_digests): `result` is what resuming checks,
/// `inputs` the tile's own inputs, kept beside the result's settled_fingerprint so that a
/// result can be recognised as still right when only a neighbour was redone.
struct ResultDigests {
  std::uint64_t result = 0, inputs = 0;
};

/// Writes the result atomically with the tile's digests.
void write_tile_result(const std::filesystem::path& file, const TileResult& result, ResultDigests digests);
/// What a result of this version says in its header it was made from, and the digest it was
/// written under; nothing when there is no such header (the rest of the file is not read, nor
/// checked: restamp_tile_result checks it).
struct ResultOrigin {
  std::uint64_t result = 0, inputs = 0, settled = 0;
  bool kept = false;  ///< last written by restamp_tile_result (kept, not processed)
};
std::optional<ResultOrigin> tile_result_origin(const std::filesystem::path& file);
/// The same of a whole result only: its magic and its checksum (which covers every section)
/// pass; nothing otherwise, quietly (what a plan of the run asks of a result it already found
/// not finished, which said why). Reads the whole file.
std::optional<ResultOrigin> whole_tile_result_origin(const std::filesystem::path& file);
/// Writes the result in `file` again under the digest `result` (atomically), marked kept and
/// unchanged otherwise; false, leaving it as it is, unless `file` holds a whole result of this
/// version (checked as resuming does) made from `made_from`'s inputs and settled fingerprint.
/// `passes`: the tile's acquisitions now (TileContents::passes). When the result names them
/// by other indices (a pass delivered late renumbered them; the inputs digest names them by
/// identity, so they are the same passes in the same order), its labels, pairs, refuted
/// copies and pieces are renumbered: the k-th of its passes becomes passes[k].
bool restamp_tile_result(const std::filesystem::path& file, const TileStore& store, const ResultOrigin& made_from,
                         std::uint64_t result, std::span<const std::uint32_t> passes);
/// Whether the result of tile `key` in `file`, made under another digest, is still right under
/// `digests`: made from the same inputs (the same passes, perhaps renumbered) and from the
/// same decisions of the earlier-phase neighbours on the tile's halo (`settled`), all the tile
/// job reads. It is then written again under digests.result (renumbered) and kept: when a
/// neighbour was redone to the same decisions along their border, or a pass delivered late
/// elsewhere renumbered the tile's passes, the tile need not be processed.
bool keep_if_still_right(const std::filesystem::path& file, const TileStore& store, TileKey key, ResultDigests digests,
                         const SettledSelection& settled);
/// Which sections of a tile result to decode (the checksum covers the whole file whatever
/// is decoded).
struct TileResultSections {
  /// The consistent pairs: only the labelled PLYs need them, and on a city they are tens of
  /// millions of pairs to decode and hold.
  bool pairs = true;
  /// The selected triangles: not when another MPI rank files them under the seam parts.
  bool selected = true;
};

/// The result in `file` when it is complete and was made under `digest`; nothing otherwise
/// (then the tile is processed again). Sections not asked for are left empty; a result made
/// before acquisitions were appended gets empty pieces for them.
std::optional<TileResult> read_tile_result(const std::filesystem::path& file, std::uint64_t digest,
                                           const TileStore& store, TileResultSections sections = {});
/// Whether `file` holds a whole result made under `digest`: its checksum (which covers every
/// section), magic, digest and section sizes pass, nothing decoded. What resuming asks of
/// every tile; a city's results took seconds to decode for that.
bool tile_result_is_finished(const std::filesystem::path& file, std::uint64_t digest, const TileStore& store);
/// Only the labels of that result (same checks; the other sections are not decoded): what
/// a later-phase neighbour needs.
std::optional<std::vector<OwnedLabel>> read_tile_labels(const std::filesystem::path& file, std::uint64_t digest,
                                                        const TileStore& store);

}  // namespace citymesh::app
