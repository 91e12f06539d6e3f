// SPDX-License-Identifier: MIT
// Stitching an output block by block: each part of it once, with what lies around it as
// frozen surroundings (StitchSurroundings), so that a part needs memory of its own size and
// the parts of one level run in parallel.
#pragma once

#include <array>
#include <cstdint>

#include "citymesh/mosaic/stitch.h"

namespace citymesh {

/// A square grid of blocks over the output, in the mesh's frame, and the bands along the
/// block sides.
struct BlockStitchParams {
  double origin_x = 0, origin_y = 0;  ///< metres: a corner of the grid
  double size = 50;                   ///< metres: a block's side
  /// metres either side of each block side: stitched after the block interiors, with them as
  /// output stitched before. At least `context`, so that the parts of one level never reach
  /// each other; less than a quarter of `size`.
  double band = 2;
  /// metres around a part from which its surroundings are taken; 0: the farthest the
  /// stitching steps of the params look (block_context()).
  double context = 0;
};

struct BlockStitchStats {
  StitchStats stitch;  ///< the whole output's open boundary before and after; counts summed over the parts
  /// per level: block interiors, bands along x = const, bands along y = const, corner squares
  std::array<std::size_t, 4> parts{};
  std::size_t largest_part = 0;        ///< triangles of the largest part with its surroundings
};

/// The farthest any step of `params` looks from a vertex (snapping, joining, clipping, the
/// gaps' perimeter), with a margin: what a part's surroundings must hold.
double block_context(const StitchParams& params);

/// Stitches `mesh` as stitch() does, part by part in four levels. First every block's
/// interior, with the bands along its sides as surroundings stitched later; then each band
/// without its ends, those along x = const before those along y = const, with what was
/// stitched before as done and the rest later; then the corner squares, with everything
/// else done. Each triangle belongs to the
/// part holding its centroid. A part sees only the triangles within the context of it; the
/// parts of a level run in parallel and the output (parts in level and grid order) is the
/// same whatever the thread count. Throws std::invalid_argument on a layout that breaks
/// the rules above.
BlockStitchStats stitch_in_blocks(MergedMesh& mesh, const StitchParams& params, const BlockStitchParams& blocks);

}  // namespace citymesh
