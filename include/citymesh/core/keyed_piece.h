// SPDX-License-Identifier: MIT
// Pieces of an output on vertices named by keys: what a seam pass keeps apart from the whole
// output (in memory or in files) and puts back together.
#pragma once

#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

#include "citymesh/core/mesh.h"

namespace citymesh {

/// The key of vertex `id` of source (acquisition) `source` in a keyed piece: keys below
/// bit 63 name input vertices so (the seam pass's cache renames their sources), the others
/// the vertices stitching makes (kNewVertexKey).
inline std::uint64_t input_vertex_key(std::uint32_t source, std::uint32_t id) {
  return std::uint64_t{source} << 32 | id;
}
/// The source of an input vertex's key (input_vertex_key).
inline std::uint32_t input_vertex_source(std::uint64_t key) { return static_cast<std::uint32_t>(key >> 32); }

/// Some triangles of an output, on vertices named by 64-bit keys (one key, one vertex of the
/// whole output, wherever it is stored), positions in the project CRS as doubles: what
/// block stitching keeps of a part between levels.
struct KeyedPiece {
  std::vector<std::uint64_t> keys;        ///< per vertex, ascending
  std::vector<Vec3d> positions, sensors;  ///< per vertex; sensors empty when the output has none
  std::vector<double> times;              ///< per vertex, or empty
  std::vector<float> intensities;         ///< per vertex, or empty
  std::vector<Rgb8> colors;               ///< per vertex, or empty
  std::vector<Triangle> triangles;        ///< on the vertices above
  std::vector<TriangleId> ids;
  std::vector<std::int32_t> source_acq, source_triangle;

  [[nodiscard]] std::size_t vertex_count() const { return keys.size(); }
  [[nodiscard]] std::size_t triangle_count() const { return triangles.size(); }
  /// The box of the triangles' corners.
  [[nodiscard]] Box3d box() const;
  /// The box of triangle t's corners.
  [[nodiscard]] Box3d box(std::size_t t) const;
  /// Appends vertex v of `from` (same attributes) with `key`, which must pass every key so far.
  void append_vertex(const KeyedPiece& from, std::uint32_t v, std::uint64_t key);
  /// Appends vertex v of mesh `m` (its attributes, which must be this piece's; positions made
  /// absolute) with `key`, which must pass every key so far.
  void append_mesh_vertex(const Mesh& m, std::uint32_t v, std::uint64_t key);
  /// Appends triangle t of `from` on the vertices `corners` of this piece.
  void append_triangle(const KeyedPiece& from, std::size_t t, const Triangle& corners);
  /// Throws ProcessingError naming `what` when the arrays disagree, keys are not ascending
  /// or a corner is out of range.
  void check(std::string_view what) const;
};

/// A digest of every array of `piece` (XXH3): equal pieces, equal digests.
std::uint64_t keyed_piece_digest(const KeyedPiece& piece);
/// The same with `head` then `tail` (one key per vertex in all) in place of the piece's keys:
/// a caller renaming some keys need not copy the others.
std::uint64_t keyed_piece_digest(const KeyedPiece& piece, std::span<const std::uint64_t> head,
                                 std::span<const std::uint64_t> tail);

/// The triangles `triangles` of `piece` (in that order) on the vertices they use.
KeyedPiece subset(const KeyedPiece& piece, std::span<const std::uint32_t> triangles);

/// The pieces as one: each key's vertex once (the first piece's copy), the triangles of each
/// piece in turn. Throws ProcessingError when the pieces carry different attributes.
KeyedPiece merge_pieces(std::span<const KeyedPiece* const> pieces);

}  // namespace citymesh
