// SPDX-License-Identifier: MIT
// Mesh simplification for the coarser levels of detail (meshoptimizer behind this header).
#pragma once

#include <cstdint>
#include <optional>
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
  /// Join the vertices of equal position first (their attribute seams, e.g. between source
  /// acquisitions, then hold no collapse: meshoptimizer never moves a position three or more
  /// vertices share); a surviving corner is then the first input vertex of its position, so a
  /// corner on such a seam may take the other side's attributes.
  bool weld = false;
};

struct SimplifiedMesh {
  std::vector<Triangle> triangles;  ///< indices into the input positions
  double error = 0.0;               ///< metres: how far the result may lie from the input
};

/// Edge-collapse simplification (meshopt_simplify). Vertices with equal positions but other
/// attributes (e.g. a source acquisition seam) collapse together along their seam. The result
/// only uses input vertices; the input order of the triangles that survive is kept by
/// meshoptimizer. Vertices flagged in `locked` (empty, or one flag per position) never move,
/// whatever `lock_border` says, except with `sloppy`, which keeps nothing in place.
SimplifiedMesh simplify_mesh(std::span<const Vec3f> positions, std::span<const Triangle> triangles,
                             const SimplifyParams& params = {}, std::span<const std::uint8_t> locked = {});

/// The digest SimplifyCache finds a result by: everything simplify_mesh() reads (positions,
/// triangles, every parameter, the lock flags) and meshoptimizer's version.
std::uint64_t simplify_digest(std::span<const Vec3f> positions, std::span<const Triangle> triangles,
                              const SimplifyParams& params, std::span<const std::uint8_t> locked = {});

/// Simplified meshes kept by simplify_digest(), e.g. between runs of an export whose tiles
/// mostly did not change. Called from several threads at once.
class SimplifyCache {
 public:
  virtual ~SimplifyCache() = default;
  [[nodiscard]] virtual std::optional<SimplifiedMesh> find(std::uint64_t digest) const = 0;
  virtual void keep(std::uint64_t digest, const SimplifiedMesh& mesh) = 0;
};

/// simplify_mesh(), looked up in `cache` first and kept there after (null: simplify_mesh()). A
/// result found that indexes past `positions` (another build's, despite the digest) is
/// simplified again.
SimplifiedMesh simplify_mesh_kept(SimplifyCache* cache, std::span<const Vec3f> positions,
                                  std::span<const Triangle> triangles, const SimplifyParams& params,
                                  std::span<const std::uint8_t> locked = {});

}  // namespace citymesh
