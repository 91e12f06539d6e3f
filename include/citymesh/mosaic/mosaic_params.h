// SPDX-License-Identifier: MIT
// Parameters of the mesh mosaic and of stitching ([mosaic] in the config).
#pragma once

#include <string_view>

namespace citymesh {

/// Per-triangle quality Q in the mosaic energy, normalised so that its mean is about 1.
enum class QualityMeasure {
  constant,    ///< 1 per triangle: more triangles per area win, so the finer mesh is favoured
  area,        ///< area / mean area: coverage wins, whatever the resolution
  resolution,  ///< area / mean area x mean edge / own longest edge: coverage at a finer resolution
};

/// How the kept triangles of the change step are merged into one mesh.
enum class MosaicMethod {
  energy,        ///< the paper's energy, solved with our QPBO (the default)
  update_model,  ///< the paper's baseline: acquisitions in date order, a triangle is kept unless
                 ///< something already kept lies within the distance threshold
};

struct MosaicParams {
  MosaicMethod method = MosaicMethod::energy;
  QualityMeasure quality = QualityMeasure::constant;
  // Lengths in the energy are counted in mean edge lengths of the input triangles, so that the
  // weights mean the same at every scan resolution: one edge of seam costs lambda 4.
  double quality_weight = 1.0;    ///< lambda 1
  double boundary_weight = 0.5;   ///< lambda 2, per mean edge length of mesh boundary kept
  double overlap_weight = 100.0;  ///< lambda 3, per pair of overlapping triangles kept
  double seam_weight = 1.0;       ///< lambda 4, per mean edge length of seam inside a mesh
  /// A seam along a crease of its mesh (the two triangles' normals more than crease_angle
  /// degrees apart) costs crease_weight times lambda 4. Pieces then end on flat surface, where
  /// clipping and zippering close the seam, rather than at a corner, where two passes cut their
  /// chamfers differently and the pieces meet as a fin. On the demo street 3x at 20 degrees
  /// takes the open seams 151 -> 115 m (docs/mosaic.md has the sweep); 1 turns it off.
  double crease_angle = 20.0;
  double crease_weight = 3.0;
  /// The quality Q of a candidate that another pass saw through (its centroid inside another
  /// acquisition's empty space, as the hole fill checks) is multiplied by this. Those are
  /// mostly facets one pass strung across a window recess that another pass saw into: they
  /// stay where nothing else is offered and yield where another source has the surface. Not
  /// zero: a surface built after an older pass is also inside that pass's empty space. On the
  /// demo street 0.2 takes the open seams 82 -> 61 m, and 723 -> 689 m over four simulated
  /// streets (docs/mosaic.md has the sweep); 1 turns it off.
  double seen_through_quality = 0.2;
  /// Group-move sweeps at most (each re-solves every acquisition once); 2 reach the fixed
  /// point on the simulated street.
  int sweeps = 2;
  /// Sweeps after the first re-solve each acquisition only within this many terms of a seam
  /// (0: everywhere). On 8 tiles of the 28 M-triangle city, 16 keep the energy within
  /// 0.005 % of re-solving everywhere (8: 0.023 %, 32: 0.004 %) with the second sweep's
  /// cuts 40 % of their size, and the mosaic 12 % faster (docs/mosaic.md).
  int later_sweep_reach = 16;
  /// Stitching joins boundaries of pieces from different sources closer than this factor
  /// times the change step's distance threshold.
  double stitch_reach = 2.0;
  /// Stitching also joins the pieces of one acquisition that share no vertex: a spinning
  /// scanner's turns, meshed one by one, leave slits and overlaps of half a triangle where one
  /// turn's piece ends and the next takes over (StitchParams::join_own_pieces), and clipping
  /// cuts the later turn back where the earlier lies within the distance threshold. Off by
  /// default: on the 30 m spinning street it takes the open boundary from 27.5 to 12.4 km and
  /// the layered ratio from 5.2 to 2.0 %, but the hole ratio from 0.96 to 1.39 % (the zipper
  /// refuses many joins between turns; docs/mosaic.md, "Stitching the turns of one pass").
  bool stitch_own_pieces = false;
  /// After the energy mosaic, kept triangles with nothing selected within the distance
  /// threshold are added back (newest acquisition first), unless another pass saw through
  /// them (fill_holes() in mosaic.h).
  bool fill_holes = true;
  /// Before stitching, the parts of pieces lying over the surface of a source with more
  /// triangles in the mosaic (within clip_reach times the distance threshold) are cut away,
  /// so that the seam between them is a meeting of boundaries the stitching can close.
  bool clip_overlaps = true;
  /// Twice the threshold: a piece cut back at the threshold itself ends hovering at the
  /// threshold over the other surface (an open seam); at twice it the demo street's open
  /// seams go 380 -> 234 m, and the static input still lies within 20 cm of the output
  /// (99.97 %, as at 1x; within 10 cm: 99.90 -> 99.85 %). docs/mosaic.md has the sweep.
  double clip_reach = 2.0;
  /// Largest angle between a piece's normal and the surface it is cut back to (degrees).
  /// Chamfers (about 45 degrees) and the small facets that one pass strings across a window
  /// recess (60 to 80) stand over the other surface and are cut; a wall on the ground (90)
  /// meets it and is not. On the demo street 60 degrees leaves 115 m of open seams, 80 leaves
  /// 82 m (docs/mosaic.md has the sweep).
  double clip_angle = 80.0;
  /// After stitching, the small holes still enclosed by boundaries of more than one source
  /// (at most gap_width times the distance threshold wide, twenty times that around) are
  /// triangulated.
  bool close_gaps = true;
  /// Three times the threshold: the gaps left between clipped boundaries are up to about
  /// two clip reaches wide; on the demo street 1x leaves 163 m of open seams, 2x 155 m, 3x
  /// 151 m and 5x the same (every fill triangle lies within 5 cm of an input surface).
  double gap_width = 3.0;
};

std::string_view quality_measure_name(QualityMeasure q);
std::string_view mosaic_method_name(MosaicMethod m);

}  // namespace citymesh
