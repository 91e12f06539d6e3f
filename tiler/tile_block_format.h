// SPDX-License-Identifier: MIT
// The tile store's block format, private to the tiler: shared by the writer (tile_store.cpp)
// and the reader (tile_block_decode.cpp).
#pragma once

#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <optional>

#include "citymesh/core/mesh.h"

namespace citymesh::tiler_detail {

inline constexpr char kMagic[8] = {'C', 'M', 'T', 'I', 'L', 'E', '0', '1'};
// Version 6: per vertex its id, position and sensor position, each coordinate as the varint
// delta of its float's bits against the previous vertex's: a block's vertices come in scan
// order, so neighbours are centimetres apart and a coordinate mostly takes two or three
// bytes instead of four. Per triangle one varint holds fan, steps bit, role and a 3-bit code
// per corner (see CornerWindow: most corners are a corner of one of the two previous
// triangles, or the block's next new vertex, and need nothing more); the other corners
// follow as varints, then the face and index only when they are not the previous triangle's
// plus one (the steps bit). A triangle mostly takes two bytes.
// Version 5 (still read) stored the corners as varint deltas against the previous corner,
// about five bytes a triangle, and the fan and role in a varint of their own. Version 4 also
// stored the positions as raw floats before the varints. Version 3 always stored the face and
// index; it was under half the size of version 2's fixed-size arrays, and the tiler's time
// went mostly into writing those. Versions 5 to 2 are still read, so that work folders and
// tile results made before stay usable. (Version 1 had an FNV-1a checksum, a tenth of the
// tiler's time on a city; no longer read.)
inline constexpr std::uint32_t kVersion = 6;
inline constexpr std::uint32_t kCornerDeltasVersion = 5;
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

/// Versions 3 to 6's header.
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
  return (version >= kCornerDeltasVersion ? 0 : 12) + attribute_bytes(flags);
}
/// Varints take at least a byte each: per vertex 7 from version 5 on (id, position, sensor)
/// and 4 before (id, sensor); per triangle 1 in version 6 (fan, step, role and corner codes),
/// 4 in versions 5 and 4 (3 corners; fan, step and role) and 6 in version 3 (3 corners, face,
/// index; fan and role).
inline std::uint64_t min_varints_per_vertex(std::uint32_t version) {
  return version >= kCornerDeltasVersion ? 7 : 4;
}
inline std::uint64_t min_varints_per_triangle(std::uint32_t version) {
  return version >= kVersion ? 1 : version >= kRawPositionsVersion ? 4 : 6;
}
/// fan << 3 | kSteps | role, from version 4 on. With kSteps set, the triangle's face and index
/// are the previous triangle's plus one and are not stored.
inline constexpr std::uint64_t kSteps = 4;

/// Version 6's corner codes, the same state kept by the writer and the reader: a corner is
/// coded 0 to 5 when it is corner k of the previous triangle (0 to 2) or of the one before
/// (3 to 5), 6 when it is the block's next new vertex (one past the largest corner so far:
/// the tiler numbers a block's vertices in order of first use), and 7 otherwise, followed by
/// a varint of its zigzag distance below the next new vertex. Strips of triangles between two
/// scan lines share two corners with one of the two triangles before and bring one new
/// vertex, so that most triangles need no corner varint at all.
class CornerWindow {
 public:
  static constexpr std::uint32_t kNew = 6, kOther = 7, kCodeBits = 3, kCodeMask = (1u << kCodeBits) - 1;
  /// A triangle's three codes, first corner highest, in the low bits of its varint.
  static constexpr std::uint32_t kTriangleCodeBits = 3 * kCodeBits;

  /// The code of `corner` (kOther: its distance below next_new() follows, zigzagged).
  [[nodiscard]] std::uint32_t code(std::uint32_t corner) const {
    for (std::uint32_t slot = 0; slot < recent_.size(); ++slot) {
      if (recent_[slot] == corner) return slot;
    }
    return corner == next_new_ ? kNew : kOther;
  }
  /// The corner that codes 0 to 6 stand for; nullopt for a slot no triangle has filled yet.
  [[nodiscard]] std::optional<std::uint64_t> corner_of(std::uint32_t code) const {
    if (code == kNew) return next_new_;
    if (recent_[code] == kEmpty) return std::nullopt;
    return recent_[code];
  }
  [[nodiscard]] std::uint64_t next_new() const { return next_new_; }
  /// After each corner, coded or decoded.
  void saw(std::uint64_t corner) { next_new_ = std::max(next_new_, corner + 1); }
  /// After each triangle.
  void shift(const Triangle& corners) {
    std::copy(recent_.begin(), recent_.begin() + 3, recent_.begin() + 3);
    std::copy(corners.begin(), corners.end(), recent_.begin());
  }

 private:
  static constexpr std::uint64_t kEmpty = UINT64_MAX;  ///< no 32-bit corner equals it
  std::array<std::uint64_t, 6> recent_{kEmpty, kEmpty, kEmpty, kEmpty, kEmpty, kEmpty};
  std::uint64_t next_new_ = 0;
};

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
