// SPDX-License-Identifier: MIT
// Clipping (internal to stitching, Turk and Levoy's step before zippering): where a piece of
// one source lies over the surface of another, the covered part of the other is cut away,
// so that the two boundaries meet instead of one lying across the other's interior.
#pragma once

#include <cstdint>

#include "citymesh/mosaic/merged_mesh.h"
#include "citymesh/mosaic/stitch.h"

namespace citymesh::mosaic_detail {

struct ClipParams {
  double tolerance = 0.1;           ///< metres: how far apart two surfaces may be and still be one
  /// Largest angle between their normals. Two meshes of one corner put their chamfers in
  /// different places, so a chamfer of one (about 45 degrees) lies over a face of the other,
  /// as do the steep facets one pass strings across a window recess; a wall on the ground
  /// (90 degrees) meets the other surface and is not cut.
  double max_angle_deg = 80.0;
  double min_edge_fraction = 0.1;   ///< a cut stays this fraction of an edge away from its ends
  /// Metres: the pieces of one source that share no vertex (source_pieces()) cut each other
  /// back too where they lie within this of each other: the later in the source's file (the
  /// later turn of a spinning scanner) yields. 0: a source never cuts itself.
  double own_tolerance = 0.0;
};

struct ClipStats {
  std::uint64_t triangles_removed = 0;  ///< covered whole
  std::uint64_t triangles_cut = 0;      ///< covered in part: replaced by their uncovered part
  std::uint64_t vertices_added = 0;     ///< where cuts cross edges
  /// With an own tolerance: triangles whose corners an earlier piece of their own source
  /// covers but whose centroid it does not, split about their centroid first.
  std::uint64_t triangles_split = 0;
};

/// A vertex of source s is covered when it lies within `tolerance` of a triangle of a source
/// of higher precedence whose normal is within `max_angle_deg` of the vertex's, and projects
/// inside it. Precedence: more triangles in the mosaic (the small pieces yield to the large
/// ones), on a tie the later acquisition; with an own tolerance, a vertex is also covered by
/// another piece of its own source lying within that tolerance, whose triangle comes before
/// every triangle of the vertex's piece at the vertex in the source's file (and a free
/// triangle whose corners are covered so, but not its centroid, is first split about its
/// centroid, so that its part over the earlier piece's hole stays).
/// Triangles with every corner covered are removed; triangles with one or two are replaced
/// by their uncovered part, cut where each edge leaves the cover (found by bisection along
/// the edge, so that the two triangles sharing an edge cut it at the same new vertex and the
/// mesh stays conforming). The parts keep their triangle's provenance and orientation. New
/// vertices interpolate every per-vertex attribute. Sources never share vertices here
/// (stitching has not started). Deterministic: triangles keep their order, each replaced in
/// place by its parts (split triangles' other parts appended). With `around`: vertices of
/// output stitched before (done) are never covered, triangles whose corners are all done or
/// later stay whole (the free triangles around a covered later vertex are cut), and
/// precedence counts each source's triangles in the whole output.
ClipStats clip_overlaps(MergedMesh& merged, const ClipParams& params, const StitchSurroundings& around = {});

}  // namespace citymesh::mosaic_detail
