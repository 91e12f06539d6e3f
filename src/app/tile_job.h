// SPDX-License-Identifier: MIT
// One tile of a tiled run: change detection and the mosaic on the tile with its halo, the
// owner's decisions written to <work>/results/<tile>.bin (and read back on resume).
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <vector>

#include "citymesh/change/detect.h"
#include "citymesh/config/config.h"
#include "citymesh/tiler/tiler.h"

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

/// A consistent pair with at least one owned member, as (acquisition, index) twice.
struct LabelPair {
  std::uint32_t a_acquisition = 0, a_index = 0, b_acquisition = 0, b_index = 0;
};

struct TileResult {
  TileKey key;
  std::vector<OwnedLabel> labels;   ///< every owned triangle, by (acquisition, index)
  std::vector<LabelPair> pairs;     ///< sorted
  /// Per acquisition, the selected owned triangles with their vertices (tile frame).
  std::vector<TilePiece> selected;
  double seconds_read = 0, seconds_detect = 0, seconds_mosaic = 0;
  std::uint64_t triangles_in_tile = 0;  ///< owned, halo and empty space
};

/// The phase of a tile: tiles of one phase never touch (no shared border or corner), so they
/// run in parallel; tiles of later phases see the decisions of their earlier neighbours.
int tile_phase(TileKey key);
inline constexpr int kTilePhases = 4;

/// Reads the tile, runs detect_changes on all of it, then the mosaic (energy or update model)
/// on its owned and halo triangles (empty-space triangles only give conflicts), and keeps the
/// owned triangles' outcome. `settled`: the labels of neighbouring tiles of earlier phases
/// (sorted by acquisition and index); their halo triangles keep the owner's choice (selected
/// ones are forced into the energy mosaic, the others are no candidates), so both sides of a
/// tile border agree.
TileResult process_tile(const TileStore& store, TileKey key, const Config& config,
                        std::span<const OwnedLabel> settled);

/// Writes the result atomically with the run's fingerprint.
void write_tile_result(const std::filesystem::path& file, const TileResult& result, std::uint64_t fingerprint);
/// The result in `file` when it is complete and was made with `fingerprint`; nothing
/// otherwise (then the tile is processed again).
std::optional<TileResult> read_tile_result(const std::filesystem::path& file, std::uint64_t fingerprint,
                                           const TileStore& store);

}  // namespace citymesh::app
