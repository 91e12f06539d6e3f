// SPDX-License-Identifier: MIT
// The tile store's block format, private to the tiler: shared by the writer (tile_store.cpp)
// and the reader (tile_block_decode.cpp).
#pragma once

#include <bit>
#include <cstdint>

#include "citymesh/core/mesh.h"

namespace citymesh::tiler_detail {

inline constexpr char kMagic[8] = {'C', 'M', 'T', 'I', 'L', 'E', '0', '1'};
// Version 4: vertex ids, sensor positions, corners, faces, fans, roles and triangle indices
// as varint deltas, which mostly take a byte each (version 3, still read, had the same), and a
// triangle whose face and index are each the previous triangle's plus one (most of a tile's
// owned triangles) stores neither: a bit beside its fan and role says so. That is two bytes
// of the six a triangle took, 12 % of a city's tile store. Version 3 was under half the size
// of version 2's fixed-size arrays, and the tiler's time went mostly into writing them.
// Versions 3 and 2 are still read, so that work folders and tile results made before stay
// usable. (Version 1 had an FNV-1a checksum, a tenth of the tiler's time on a city; no
// longer read.)
inline constexpr std::uint32_t kVersion = 4;
inline constexpr std::uint32_t kFullIdsVersion = 3;
inline constexpr std::uint32_t kFixedVersion = 2;
inline constexpr std::uint32_t kHasIntensity = 1, kHasColor = 2;

/// What both versions begin with.
struct BlockStart {
  char magic[8];
  std::uint32_t version;
  std::uint32_t flags;
};

/// Versions 3 and 4's header.
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

/// Bytes per vertex of the attributes stored as they are (versions 3 and 4: positions,
/// intensities, colours).
inline std::uint64_t raw_vertex_bytes(std::uint32_t flags) {
  return 12 + ((flags & kHasIntensity) != 0 ? 4 : 0) + ((flags & kHasColor) != 0 ? 3 : 0);
}
/// Varints take at least a byte each: 4 per vertex (id, sensor x, y, z) and per triangle 4 in
/// version 4 (3 corners; fan, step and role) and 6 in version 3 (3 corners, face, index; fan
/// and role).
inline constexpr std::uint64_t kMinVarintsPerVertex = 4;
inline std::uint64_t min_varints_per_triangle(std::uint32_t version) { return version == kVersion ? 4 : 6; }
/// Version 4's last varint of a triangle: fan << 3 | kSteps | role. With kSteps set, its face
/// and index are the previous triangle's plus one and are not stored.
inline constexpr std::uint64_t kSteps = 4;
/// Version 2's fixed sizes.
inline std::uint64_t fixed_vertex_bytes(std::uint32_t flags) { return 4 + 12 + raw_vertex_bytes(flags); }
inline constexpr std::uint64_t kFixedTriangleBytes = 12 + 8 + 4 + 4 + 1;

/// The block flags of the per-vertex attributes present.
inline std::uint32_t attribute_flags(bool has_intensities, bool has_colors) {
  return (has_intensities ? kHasIntensity : 0) | (has_colors ? kHasColor : 0);
}

inline std::uint32_t flags_of(const Mesh& m) { return attribute_flags(!m.intensities.empty(), !m.colors.empty()); }

inline std::uint32_t float_bits(float v) { return std::bit_cast<std::uint32_t>(v); }

}  // namespace citymesh::tiler_detail
