// SPDX-License-Identifier: MIT
// The tiler: streams each acquisition once, with bounded buffers, onto the tile grid and
// writes the tile store (chunk files per tile and acquisition, then a manifest).
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
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
  std::filesystem::path dir;                ///< the tile store folder; emptied first
  std::uint64_t buffer_bytes = 256ull << 20;  ///< buffered triangles are flushed past this
};

/// What the store holds for one tile: triangles per acquisition and role (owned, halo, empty space).
struct TileContents {
  TileKey key;
  std::vector<std::array<std::uint64_t, 3>> triangles;
  [[nodiscard]] std::uint64_t owned() const;
  [[nodiscard]] std::uint64_t total() const;
};

struct TilingStats {
  std::uint64_t input_bytes = 0, halo_copies = 0, empty_space_copies = 0, blocks = 0, bytes_written = 0;
  double seconds = 0;
};

struct TileStore {
  std::filesystem::path dir;
  TileGridParams grid;
  std::vector<std::uint64_t> triangles;  ///< per acquisition: its triangles (PlyReader's order)
  std::vector<TileContents> tiles;       ///< tiles owning at least one triangle, in key order
  TilingStats stats;
  std::string fingerprint;  ///< what the caller says the store was made from
};

/// Streams every acquisition once and writes <dir>/<tile>/<acquisition>.bin; each triangle goes
/// to the tile owning its centroid, as halo to the tiles within `halo`, and as empty space to
/// the other tiles its tetrahedron with the viewpoint (the barycentre of its vertices' sensor
/// positions) crosses. Vertices of one acquisition are held whole (positions, sensor positions
/// and attributes: ~60 bytes each); triangles are buffered up to `buffer_bytes`. Throws
/// InputError naming the file on malformed input, OutputError when the store cannot be written.
TileStore tile_acquisitions(std::span<const Acquisition> acquisitions, const TilerParams& params);

/// The chunk file of one acquisition in one tile (it may not exist: nothing of it there).
std::filesystem::path tile_chunk_path(const std::filesystem::path& dir, TileKey key, std::uint32_t acquisition);

/// Writes <store.dir>/manifest.json atomically: the store counts as finished only then.
void write_tile_manifest(const TileStore& store);
/// The finished store in `dir`, or nothing when it has no manifest. Throws InputError naming
/// the manifest when it is malformed.
std::optional<TileStore> read_tile_manifest(const std::filesystem::path& dir);

/// Reads one tile: a piece per acquisition (empty when the tile holds none of it), all in the
/// frame of the tile's corner.
std::vector<TilePiece> read_tile(const TileStore& store, TileKey key);

}  // namespace citymesh
