// SPDX-License-Identifier: MIT
// The tile store's block format, private to the tiler: shared by the writer (tile_store.cpp)
// and the reader (tile_block_decode.cpp).
#pragma once

#include <bit>
#include <cstdint>

#include "citymesh/core/mesh.h"

namespace citymesh::tiler_detail {

inline constexpr char kMagic[8] = {'C', 'M', 'T', 'I', 'L', 'E', '0', '1'};
// Version 5: per vertex its id, position and sensor position, each coordinate as the varint
// delta of its float's bits against the previous vertex's: a block's vertices come in scan
// order, so neighbours are centimetres apart and a coordinate mostly takes two or three
// bytes instead of four (a fifth of a city's tile store). Per triangle its corners, then
// fan << 3 | steps << 2 | role, and its face and index only when they are not the previous
// triangle's plus one (the steps bit).
// Version 4 (still read) stored the positions as raw floats before the varints. Version 3
// (still read) always stored the face and index, two bytes of the six a triangle took; it was
// under half the size of version 2's fixed-size arrays, and the tiler's time went mostly into
// writing those. Versions 4, 3 and 2 are still read, so that work folders and tile results
// made before stay usable. (Version 1 had an FNV-1a checksum, a tenth of the tiler's time on a
// city; no longer read.)
inline constexpr std::uint32_t kVersion = 5;
inline constexpr std::uint32_t kRawPositionsVersion = 4;
inline constexpr std::uint32_t kFullIdsVersion = 3;
inline constexpr std::uint32_t kFixedVersion = 2;
inline constexpr std::uint32_t kHasIntensity = 1, kHasColor = 2;

/// What every version begins with.
struct BlockStart {
  char magic[8];
  std::uint32_t version;
  std::uint32_t flags;
};

/// Versions 3 to 5's header.
struct BlockHeader {
  BlockStart start;
  std::uint64_t vertices;
  std::uint64_t triangles;
  std::uint64_t payload_bytes;
  std::uint64_t checksum;  ///< bulk_checksum (XXH3) of the payload
};
static_assert(sizeof(BlockHeader) == 48);

/// Version 2's header: the payload's size follows from the counts.
struct FixedBlockHeader {
  BlockStart start;
  std::uint64_t vertices;
  std::uint64_t triangles;
  std::uint64_t checksum;
};
static_assert(sizeof(FixedBlockHeader) == 40);

/// Bytes per vertex of the optional attributes, stored as they are (intensities, colours).
inline std::uint64_t attribute_bytes(std::uint32_t flags) {
  return ((flags & kHasIntensity) != 0 ? 4 : 0) + ((flags & kHasColor) != 0 ? 3 : 0);
}
/// Bytes per vertex stored as they are in a varint block: versions 3 and 4 also had the
/// position's three floats there.
inline std::uint64_t raw_vertex_bytes(std::uint32_t flags, std::uint32_t version) {
  return (version >= kVersion ? 0 : 12) + attribute_bytes(flags);
}
/// Varints take at least a byte each: per vertex 7 in version 5 (id, position, sensor) and 4
/// before (id, sensor); per triangle 4 from version 4 on (3 corners; fan, step and role) and 6
/// in version 3 (3 corners, face, index; fan and role).
inline std::uint64_t min_varints_per_vertex(std::uint32_t version) { return version >= kVersion ? 7 : 4; }
inline std::uint64_t min_varints_per_triangle(std::uint32_t version) {
  return version >= kRawPositionsVersion ? 4 : 6;
}
/// The last varint of a triangle from version 4 on: fan << 3 | kSteps | role. With kSteps set,
/// its face and index are the previous triangle's plus one and are not stored.
inline constexpr std::uint64_t kSteps = 4;
/// Version 2's fixed sizes.
inline std::uint64_t fixed_vertex_bytes(std::uint32_t flags) { return 4 + 12 + 12 + attribute_bytes(flags); }
inline constexpr std::uint64_t kFixedTriangleBytes = 12 + 8 + 4 + 4 + 1;

/// The block flags of the per-vertex attributes present.
inline std::uint32_t attribute_flags(bool has_intensities, bool has_colors) {
  return (has_intensities ? kHasIntensity : 0) | (has_colors ? kHasColor : 0);
}

inline std::uint32_t flags_of(const Mesh& m) { return attribute_flags(!m.intensities.empty(), !m.colors.empty()); }

inline std::uint32_t float_bits(float v) { return std::bit_cast<std::uint32_t>(v); }

}  // namespace citymesh::tiler_detail
