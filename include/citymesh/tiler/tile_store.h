// SPDX-License-Identifier: MIT
// The tile store's blocks: one acquisition's triangles in one tile, as the tiler wrote them
// (each flush of its buffers appends one block per tile to the acquisition's block file), read
// back together by tile processing.
#pragma once

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "citymesh/core/mesh.h"
#include "citymesh/core/read_file.h"

namespace citymesh {

/// Why a triangle is in a tile. Owned: its centroid lies in the tile (exactly one tile owns
/// each triangle; only the owner writes its result). Halo: it lies within the halo of the tile
/// (context for consistency and the mosaic). Empty space: only its tetrahedron with the
/// viewpoint crosses the tile (it can make a triangle of the tile conflict).
enum class TileRole : std::uint8_t { owned = 0, halo = 1, empty_space = 2 };

/// One acquisition's part of one tile: a mesh in the tile's local frame (origin: the tile's
/// corner) with sensor positions and, per triangle, its global id, its index in the
/// acquisition (the order of PlyReader's triangles) and its role; per vertex its index in the
/// acquisition's file, so that blocks written at different times share vertices again.
struct TilePiece {
  Mesh mesh;
  std::vector<std::uint32_t> vertex_ids;
  std::vector<std::uint32_t> triangle_index;
  std::vector<TileRole> roles;

  [[nodiscard]] std::size_t triangle_count() const { return mesh.triangle_count(); }
  void clear();
};

/// `piece` as one checksummed block: header (magic, version 3, attribute flags, counts,
/// payload size, XXH3 of the payload) and payload (positions and attributes as they are, then
/// varint deltas of vertex ids, sensor positions, corners, faces, triangle indices, fans and
/// roles: mostly a byte each).
std::string encode_tile_block(const TilePiece& piece);

/// The blocks in `bytes` merged into one piece (see read_tile_piece); `source` names them in
/// errors.
TilePiece decode_tile_blocks(std::string_view bytes, const Vec3d& origin, std::uint32_t acquisition,
                             std::string_view source);

/// fsyncs every file under `dir` (and the folders): the tile store is durable once this returns.
void sync_tile_files(const std::filesystem::path& dir);

/// Reads the blocks at `blocks` of `file` (one acquisition's block file) into one piece in
/// the frame `origin`: vertices of several blocks with the same id become one (the first
/// block's copy), triangles keep the order in which they were written. Global ids get
/// `acquisition`. Throws InputError naming the file, `tile` and the block when a block passes
/// the file's end, is truncated, has another magic or version, a count that does not fit, an
/// index out of range or a checksum that does not match.
TilePiece read_tile_piece(const std::filesystem::path& file, std::span<const ByteRange> blocks, const Vec3d& origin,
                          std::uint32_t acquisition, std::string_view tile);

}  // namespace citymesh
