// SPDX-License-Identifier: MIT
// Stitching (paper §IV): the selected triangles form pieces, one source each; where the
// boundaries of pieces from different sources (or different pieces of one source) face each
// other, strips of new triangles join them (zippering), and vertices closer than a small
// tolerance are merged.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>

#include "citymesh/mosaic/merged_mesh.h"

namespace citymesh {

struct StitchParams {
  double snap = 0.1;    ///< metres: boundaries of different sources closer than this share vertices
  double reach = 0.2;   ///< metres: boundaries of different sources closer than this are joined
  double weld = 0.005;  ///< metres: strip corners closer than this become one vertex
  /// metres: where a piece lies within this of a larger source's surface (normals within
  /// clip_angle), the covered part is cut away first so that the boundaries meet; 0: off
  double clip = 0.0;
  double clip_angle = 80.0;  ///< degrees
  /// metres: small holes left between pieces of several sources, up to this wide (and 20
  /// times this around), are triangulated last; 0: off
  double gap = 0.0;
  /// Whether the pieces of one source that share no vertex (source_pieces(): the turns of a
  /// spinning scanner, meshed one by one) are stitched to each other as pieces of different
  /// sources are, after those (a boundary vertex is joined to another source's first). Off:
  /// only pieces of different sources are joined.
  bool join_own_pieces = false;
  /// Metres, with join_own_pieces: where two pieces of one source lie within this of each
  /// other (normals within clip_angle), clipping cuts back the one later in the source's file
  /// (the later turn); 0: they are not clipped.
  double own_clip = 0.0;
};

struct StitchStats {
  double open_boundary_before = 0, open_boundary_after = 0;  ///< metres of edges used by one triangle
  std::uint64_t vertices_snapped = 0;  ///< boundary vertices of two sources made one
  std::uint64_t edges_split = 0;       ///< boundary edges split at vertices of another source
  std::uint64_t triangles_uncovered = 0;  ///< covered whole by a larger source: removed
  std::uint64_t triangles_clipped = 0;    ///< covered in part: cut back to the uncovered part
  /// A later turn's triangles spanning an earlier turn's hole, split about their centroid
  /// before clipping (join_own_pieces with own_clip only)
  std::uint64_t triangles_split = 0;
  std::uint64_t strips = 0, triangles_added = 0, vertices_welded = 0;
  std::uint64_t gaps_filled = 0;  ///< small holes between sources closed (their triangles count in triangles_added)
  /// Snaps and strip triangles refused (a flip, a degenerate triangle or a reused directed edge).
  std::uint64_t rejected = 0;
  double seconds = 0;
};

/// StitchStats' counts, which add up over the parts of a seam pass, in the order its cache
/// stores them (a count added goes last, with a new cache magic).
inline constexpr std::array kStitchCounts{
    &StitchStats::vertices_snapped,  &StitchStats::edges_split, &StitchStats::triangles_uncovered,
    &StitchStats::triangles_clipped, &StitchStats::strips,      &StitchStats::triangles_added,
    &StitchStats::vertices_welded,   &StitchStats::gaps_filled, &StitchStats::rejected,
    &StitchStats::triangles_split};

/// A vertex's part in a seam pass over one part of an output, when the output is stitched
/// part by part (each part's triangles once, with what lies around them).
enum class VertexRole : std::uint8_t {
  free = 0,   ///< of this part's triangles only: stitching may move it, merge it, cut it away
  done = 1,   ///< of output stitched before: stays as it is; this part's seams may join it
  /// of a part stitched afterwards (and not done): stays where it is; the free triangles
  /// around it may be cut back from it; seams are joined to it only where this part's
  /// triangles use it too (on the border between the two parts), the rest is that part's
  later = 2,
  /// of this part and of a part stitched at the same time, or on the edge of what a part
  /// sees of the output: stays where it is, no seam joins it (the part stitched after both
  /// does); the free triangles around it may be cut back from it
  held = 3,
};

/// The role of vertex v in `roles` (a StitchSurroundings::vertex_roles): free past its end.
inline VertexRole role_of(std::span<const std::uint8_t> roles, std::uint32_t v) {
  return v < roles.size() ? static_cast<VertexRole>(roles[v]) : VertexRole::free;
}

/// Whether every corner of `tri` belongs to other parts (a role other than free in `roles`):
/// such a triangle is frozen, it stays as it is.
inline bool all_corners_frozen(const Triangle& tri, std::span<const std::uint8_t> roles) {
  const auto frozen = [&](std::uint32_t v) { return role_of(roles, v) != VertexRole::free; };
  return frozen(tri[0]) && frozen(tri[1]) && frozen(tri[2]);
}

/// What a seam pass over one part of an output needs to know of the rest.
struct StitchSurroundings {
  /// Per vertex of the mesh (VertexRole; vertices past its end are free). Triangles whose
  /// corners are all done or later come out unchanged; new triangles may use done vertices
  /// and the joinable later ones.
  /// Later triangles are there for clipping (what they cover of this part is cut now) and so
  /// that this part's edges along them are not taken for seams.
  std::span<const std::uint8_t> vertex_roles = {};
  /// Per source: its triangles in the whole output, which decide who yields where two
  /// overlap (clipping); empty: counted in the mesh itself.
  std::span<const std::uint64_t> source_sizes = {};
  /// Where the part's own triangles start, when the mesh holds the other parts' first (done
  /// or later); unset: the part's triangles are told by their vertices alone. Told, a
  /// triangle of the part whose corners are all frozen is still removed when a larger
  /// source covers it whole (no part after it could).
  std::optional<std::size_t> first_own_triangle = {};

  /// Whether triangle t is told to be the part's own (at or past first_own_triangle).
  [[nodiscard]] bool told_own(std::size_t t) const { return first_own_triangle && t >= *first_own_triangle; }
};

/// Closes the seams between pieces of different sources of `mesh` (and, with `join_own_pieces`,
/// between the pieces of one source that share no vertex). With `clip` > 0, the parts
/// of pieces lying over a larger source's surface are first cut away (Turk and Levoy's
/// clipping), so that a piece's boundary no longer runs across another's interior. Boundaries lying within
/// `snap` of each other are first made to share vertices (nearby boundary vertices merged at
/// their midpoint, then boundary edges split at the other side's vertices: the split pieces
/// keep their provenance); the boundaries still facing each other within `reach` are then
/// joined with strips of new triangles (source kNoSource), advancing along both boundaries
/// and taking the shorter diagonal at each step. With `gap` > 0, the small holes still
/// enclosed by boundaries of several sources are then triangulated. No operation may flip or degenerate a
/// triangle or use a directed edge twice. `around` freezes what was stitched before (see
/// StitchSurroundings). Deterministic.
StitchStats stitch(MergedMesh& mesh, const StitchParams& params, const StitchSurroundings& around = {});

/// Total length of the edges used by exactly one triangle.
double open_boundary_length(const Mesh& mesh);

}  // namespace citymesh
