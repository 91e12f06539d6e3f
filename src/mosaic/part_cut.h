// SPDX-License-Identifier: MIT
// Internal to the mosaic module: one part of a block stitching cut out, with the triangles
// around it, as a mesh stitch() takes; and its stitched triangles taken back out as a keyed
// piece.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "citymesh/mosaic/stitch_blocks.h"

namespace citymesh::mosaic_detail {

/// A part loaded around the one being stitched, and what its triangles are to that one.
struct Neighbour {
  std::shared_ptr<const KeyedPiece> piece;
  VertexRole role = VertexRole::later;  ///< done, held or later
};

/// A part cut out with its surroundings (first), ready for stitch().
struct PartCut {
  MergedMesh merged;                      ///< in the frame of the cut (merged.mesh.origin)
  std::vector<std::uint64_t> keys;        ///< per vertex as cut out, ascending
  std::vector<Vec3d> positions, sensors;  ///< per vertex as cut out: the doubles its floats were made from
  std::vector<std::uint8_t> roles;        ///< per vertex as cut out: its VertexRole
  std::vector<Triangle> surroundings;     ///< the other parts' triangles, as cut out (the first ones)
};

/// Cuts `own` out with every triangle of `around` whose box meets `reach` (own's box grown by
/// the context), in the frame `origin`. Vertices come in key order. A vertex takes the
/// strongest role of the triangles using it (held over done over later over free); one used
/// by triangles that were not cut out is held (the output looks open there and is not), and
/// so is one outside `reach`, whose users may not all have been loaded. Every part whose box
/// meets `reach` must be in `around`: then every user of a vertex inside it is.
PartCut cut_part(const KeyedPiece& own, std::span<const Neighbour> around, const Box3d& reach, const Vec3d& origin);

/// The part's own triangles once `cut` is stitched, on their vertices: a cut vertex keeps its
/// key (and its double position unless stitching moved it), a new one gets the key
/// kNewVertexKey | part << 32 | k.
KeyedPiece stitched_piece(const PartCut& cut, std::uint64_t part);

}  // namespace citymesh::mosaic_detail
