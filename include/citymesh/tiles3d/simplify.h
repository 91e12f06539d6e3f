// SPDX-License-Identifier: MIT
// Mesh simplification for the coarser levels of detail (meshoptimizer behind this header).
#pragma once

#include <span>
#include <vector>

#include "citymesh/core/mesh.h"

namespace citymesh {

struct SimplifyParams {
  double target_ratio = 0.25;  ///< keep about this fraction of the triangles
  /// Stop before the error exceeds this fraction of the mesh's extent.
  double max_error_fraction = 0.02;
  /// Keep vertices on open borders in place, so that neighbouring simplified tiles (and
  /// their finer neighbours) still meet without cracks.
  bool lock_border = true;
  /// Cluster vertices instead of collapsing edges (meshopt_simplifySloppy): reaches its target
  /// on any mesh, fragments and loose triangles included, but keeps no border nor topology.
  bool sloppy = false;
};

struct SimplifiedMesh {
  std::vector<Triangle> triangles;  ///< indices into the input positions
  double error = 0.0;               ///< metres: how far the result may lie from the input
};

/// Edge-collapse simplification (meshopt_simplify). Vertices with equal positions but other
/// attributes (e.g. a source acquisition seam) collapse together along their seam. The result
/// only uses input vertices; the input order of the triangles that survive is kept by
/// meshoptimizer.
SimplifiedMesh simplify_mesh(std::span<const Vec3f> positions, std::span<const Triangle> triangles,
                             const SimplifyParams& params = {});

}  // namespace citymesh
