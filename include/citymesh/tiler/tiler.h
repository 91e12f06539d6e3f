// SPDX-License-Identifier: MIT
// The tiler: streams each acquisition once, with bounded buffers, onto the tile grid and
// writes the tile store: a folder per acquisition (its block file and a summary saying where
// each tile's blocks lie), then a manifest. Acquisitions are tiled independently, so the processes of a cluster share
// them.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "citymesh/core/mesh.h"
#include "citymesh/io/ply_reader.h"
#include "citymesh/tiler/tile_grid.h"
#include "citymesh/tiler/tile_store.h"

namespace citymesh {

struct TilerParams {
  TileGridParams grid;
  PlyReadParams ply;
  std::filesystem::path dir;                  ///< the tile store folder
  std::uint64_t buffer_bytes = 256ull << 20;  ///< buffered triangles are flushed past this
};

/// What the store holds for one tile: triangles per acquisition and role (owned, halo, empty
/// space), and where they lie.
struct TileContents {
  TileKey key;
  std::vector<std::array<std::uint64_t, 3>> triangles;
  /// Per acquisition: the tile's blocks in its block file, in the order they were written.
  std::vector<std::vector<ByteRange>> blocks;
  [[nodiscard]] std::uint64_t owned() const;
  [[nodiscard]] std::uint64_t total() const;
  /// The acquisitions the tile holds triangles of (any role), by index.
  [[nodiscard]] std::vector<std::uint32_t> passes() const;
};

struct TilingStats {
  std::uint64_t input_bytes = 0, halo_copies = 0, empty_space_copies = 0, blocks = 0, bytes_written = 0;
  double seconds = 0;
  /// Metres: the largest x-y distance from a triangle's centroid to one of its corners (its
  /// radius about the centroid). A tile's halo holds every partner and every point of its
  /// owned triangles while this plus the distance threshold stays within the halo.
  double largest_radius = 0;
};

struct TileStore {
  std::filesystem::path dir;
  TileGridParams grid;
  std::vector<std::uint64_t> triangles;  ///< per acquisition: its triangles (PlyReader's order)
  std::vector<TileContents> tiles;       ///< tiles owning at least one triangle, in key order
  TilingStats stats;
  std::string fingerprint;  ///< what the caller says the store was made from

  /// Tile `key`'s contents (by bisection over the sorted tiles); null when it owns nothing.
  [[nodiscard]] const TileContents* find(TileKey key) const {
    const auto it =
        std::lower_bound(tiles.begin(), tiles.end(), key, [](const TileContents& t, TileKey k) { return t.key < k; });
    return it != tiles.end() && it->key == key ? &*it : nullptr;
  }
};

/// What one acquisition holds in one tile.
struct AcquisitionTile {
  std::array<std::uint64_t, 3> counts{};  ///< triangles per role
  std::vector<ByteRange> blocks;          ///< its blocks in the block file, in the order written
  friend bool operator==(const AcquisitionTile&, const AcquisitionTile&) = default;
};

/// What tiling one acquisition gave (its <dir>/a<k>/summary.json).
struct AcquisitionTiling {
  std::uint64_t triangles = 0;               ///< the acquisition's triangles
  std::map<TileKey, AcquisitionTile> tiles;  ///< the tiles it has triangles in
  TilingStats stats;
  std::string fingerprint;  ///< what the caller says the tiling was made from
};

/// Where acquisitions are tiled (<dir>/staging/a<k>.<process tag>) before they are renamed
/// into place.
inline constexpr const char* kStagingFolder = "staging";

/// Streams one acquisition once and writes <dir>/a<k>/blocks.bin; each triangle goes
/// to the tile owning its centroid, as halo to the tiles within `halo`, and as empty space to
/// the other tiles its tetrahedron with the viewpoint (the barycentre of its vertices' sensor
/// positions) crosses. Vertices of one acquisition are held whole (positions, sensor positions
/// and attributes: ~60 bytes each); triangles are buffered up to `buffer_bytes`. One file holds
/// every tile's blocks: a file per tile and acquisition made a city's store hundreds of
/// thousands of files, and creating them was up to a fifth of the tiler's time. The folder is
/// built under <dir>/staging/ with a name unique to this process and renamed into place with
/// its summary, so it counts as finished only whole. Processes sharing `dir` may tile the same
/// acquisition at once: the first to finish wins and the others keep its copy (the tiler is
/// deterministic, so the bytes are the same). Throws InputError naming the file on malformed
/// input, OutputError when the store cannot be written.
AcquisitionTiling tile_acquisition(const Acquisition& acquisition, const TilerParams& params,
                                   const std::string& fingerprint);

/// The finished tiling of acquisition `k` in `dir` made with `fingerprint`, or nothing.
std::optional<AcquisitionTiling> read_acquisition_tiling(const std::filesystem::path& dir, std::uint32_t acquisition,
                                                         const std::string& fingerprint);

/// The store made of every acquisition's tiling (`parts[k]`: acquisition k).
TileStore assemble_tile_store(const std::filesystem::path& dir, const TileGridParams& grid,
                              std::span<const AcquisitionTiling> parts, std::string fingerprint);

/// Removes from `dir` what a store of the acquisitions tiled with `acquisition_fingerprints`
/// (one each, in order) does not use: a manifest made with another `store_fingerprint`,
/// acquisition folders of another fingerprint or beyond the count, older layouts; with
/// `staging` also unfinished staging folders (only when no other process can be tiling into
/// `dir`). Acquisitions are fingerprinted one by one so that adding one keeps the others' tiling.
void prune_tile_store(const std::filesystem::path& dir, std::span<const std::string> acquisition_fingerprints,
                      const std::string& store_fingerprint, bool staging);

/// Moves the tiling of each acquisition whose folder in `dir` holds another's to its own
/// folder, found by its fingerprint (`acquisition_fingerprints`, one per acquisition in order,
/// which name the acquisition without its index): a pass delivered late, or one removed
/// before others, renumbers the passes after it, whose tiling is then moved rather than made
/// again. Only for a process that owns `dir` (no other may be tiling or reading there).
/// Returns the number of folders moved; throws OutputError when one cannot be.
std::size_t move_renumbered_tilings(const std::filesystem::path& dir,
                                    std::span<const std::string> acquisition_fingerprints);

/// The bytes tiling `acquisition` reads: its file's size; 0 when it is withdrawn (not read)
/// or cannot be read (tile_acquisition says why). Used to hand out the largest first.
std::uint64_t acquisition_bytes(const Acquisition& acquisition);

/// Empties `params.dir`, tiles every acquisition, largest file first and `at_once` at a time
/// (each alone, with its own buffers: the store's bytes do not depend on it), and assembles
/// the store (without a fingerprint or manifest).
TileStore tile_acquisitions(std::span<const Acquisition> acquisitions, const TilerParams& params, unsigned at_once = 1);

/// The folder of one acquisition in the store.
std::filesystem::path acquisition_tiles_path(const std::filesystem::path& dir, std::uint32_t acquisition);
/// The block file of one acquisition: every tile's blocks, in the order the tiler wrote them.
std::filesystem::path acquisition_blocks_path(const std::filesystem::path& dir, std::uint32_t acquisition);

/// Writes <store.dir>/manifest.json atomically: the store counts as finished only then.
void write_tile_manifest(const TileStore& store);
/// The finished store in `dir`, or nothing when it has no manifest, one of an older layout, or
/// a damaged one (it does not parse, or its checksum does not match: said in a warning); its
/// acquisitions are then tiled again. Throws InputError naming the manifest when it is of a
/// newer layout, or checksummed but inconsistent (a fault of citymesh).
std::optional<TileStore> read_tile_manifest(const std::filesystem::path& dir);

/// Reads one tile: a piece per acquisition (empty when the tile holds none of it), all in the
/// frame of the tile's corner.
std::vector<TilePiece> read_tile(const TileStore& store, TileKey key);

}  // namespace citymesh
