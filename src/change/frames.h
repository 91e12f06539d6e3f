// SPDX-License-Identifier: MIT
// Internal to the change module: per-triangle quantities every step needs, computed once, and
// the steps of detect_changes as free functions.
#pragma once

#include <array>
#include <vector>

#include "citymesh/change/detect.h"
#include "citymesh/core/geometry.h"
#include "citymesh/spatial/box_tree.h"
#include "citymesh/spatial/occupancy_grid.h"
#include "citymesh/spatial/voxel_mask.h"

namespace citymesh::change_detail {

/// Derived per global triangle, in the meshes' shared local frame.
struct TriangleFrames {
  std::vector<TimePoint> dates;  ///< per acquisition
  GlobalTriangles index;
  std::vector<std::array<Vec3f, 3>> corner;  ///< copied out of the meshes for locality
  std::vector<Vec3f> centroid;
  std::vector<Vec3f> normal;     ///< unit, turned towards the viewpoint
  std::vector<Vec3f> viewpoint;  ///< barycentre of the corners' sensor positions
  /// The empty space kept after the conflict margin is the tetrahedron scaled about the
  /// viewpoint by this factor (exactly the points at least `margin` from the triangle's plane);
  /// 0 when the viewpoint is within the margin of the plane (no empty space).
  std::vector<float> empty_scale;
  /// The corners' box, padded (see bounds()): asked for once per newer acquisition and by
  /// every step, so kept rather than recomputed.
  std::vector<Box3f> box;
  std::vector<TriangleUse> use;  ///< per global triangle; empty: every one labelled

  [[nodiscard]] std::size_t size() const { return centroid.size(); }
  /// Whether triangle g's own labels are wanted: it queries the consistency search and is
  /// tested for conflicts.
  [[nodiscard]] bool asks(std::size_t g) const { return use.empty() || use[g] != TriangleUse::empty_space; }
  /// Whether g's conflicts raise the refutes of the triangles whose empty space it meets.
  [[nodiscard]] bool raises_refutes(std::size_t g) const { return use.empty() || use[g] == TriangleUse::labelled; }
  [[nodiscard]] std::size_t acquisitions() const { return dates.size(); }
  /// Whether acquisition a has any triangle here (a tile may hold none of a pass that
  /// covers only part of the city: such a pass has no empty space to ask about).
  [[nodiscard]] bool holds(std::size_t a) const { return index.offsets[a] < index.offsets[a + 1]; }
  [[nodiscard]] TriangleCorners corners(std::size_t g) const;
  [[nodiscard]] TetrahedronCorners empty_space(std::size_t g) const;
  /// The corners' box, padded by a hair so that rounding to float never loses a touching pair.
  [[nodiscard]] const Box3f& bounds(std::size_t g) const { return box[g]; }
  [[nodiscard]] TimePoint date_of(std::size_t g) const { return dates[index.acquisition_of(g)]; }
};

/// The factor about the viewpoint that turns triangle c's tetrahedron into its empty space
/// (TriangleFrames::empty_scale): (h - margin) / h keeps exactly the points at least
/// conflict_margin from c's plane (h: the viewpoint's height above it); with
/// EmptySpaceReach::nearest_sample it is also at most (nearest corner's range - margin) /
/// farthest corner's range, so that no point lies farther from the viewpoint than the nearest
/// corner less the margin. 0 (no empty space) when h is within the margin.
double empty_space_scale(const TriangleCorners& c, const Vec3d& viewpoint, double height, const ChangeParams& params);

/// Cuts of about `length` metres along an empty space q (viewpoint first), at least 1.
int slab_count(const TetrahedronCorners& q, double length);
/// The boxes of the slabs of one empty space q (viewpoint first). Slab k of n is the part
/// between k/n and (k+1)/n of the way from the viewpoint; its box is that of the hull of the
/// two cross-sections there, which holds the slab since the empty space is convex, padded so
/// that rounding to float loses nothing. Each box costs a few operations per axis instead of
/// a pass over six points (the grids ask for tens of slabs per empty space), and is the same
/// to the bit: a cross-section's extreme along an axis is the viewpoint plus the scale times
/// the extreme of the edge vectors, and rounding keeps that order.
class EmptySpaceSlabs {
 public:
  explicit EmptySpaceSlabs(const TetrahedronCorners& q);
  [[nodiscard]] Box3f slab(int k, int n) const { return between(double(k) / n, double(k + 1) / n); }
  /// The box of the part between s0 and s1 (0 <= s0 <= s1 <= 1) of the way from the
  /// viewpoint. The box of a stretch holds the box of every part of it, to the bit: each step
  /// of the computation rounds monotonically.
  [[nodiscard]] Box3f between(double s0, double s1) const;

 private:
  Vec3d apex_, low_, high_;  ///< the viewpoint; per axis, the least and greatest edge vector
};

/// Checks the input and computes every frame (parallel, deterministic).
TriangleFrames prepare_triangles(const ChangeInput& input, const ChangeParams& params);

/// Overlapping triangles: pairs whose normals are within normal_angle and where one's
/// centroid lies within distance_threshold of the other's plane and projects inside it
/// (point-to-triangle distance reached inside). Candidates come from point queries in a BVH
/// of every triangle's prism box (the triangle thickened by the threshold along its normal),
/// which holds exactly the points that can pass the test. Only triangles that ask
/// (TriangleFrames::asks) query: a pair of which only an empty-space triangle overlaps the
/// other is not found. Each list sorted, each pair once.
struct OverlappingPairs {
  /// Of different acquisitions: the consistent pairs (labels and the mosaic's overlap terms).
  std::vector<TrianglePair> consistent;
  /// Of one acquisition, sharing no corner: two layers of one pass (overlapping frames of a
  /// spinning scanner, a vehicle crossing its own path). The mosaic's overlap terms only.
  std::vector<TrianglePair> layers;
};
OverlappingPairs find_overlapping_pairs(const TriangleFrames& frames, const ChangeParams& params, ChangeStats& stats);

/// The voxels of every box a grid is ever asked about: those of the triangles older than the
/// newest acquisition (the pre-filter and the unconfirmed policy ask about nothing else).
VoxelMask asked_voxels(const TriangleFrames& frames, double voxel_size);

/// Per acquisition, a sparse voxel grid marking the voxels its (margin-reduced) empty space
/// crosses, wherever `asked` holds them (a default VoxelMask: everywhere). Conservative: a
/// voxel not marked holds none of that empty space, or is not asked about. Marking only where
/// questions come gives the same answers to them, for a third less time (docs/change-detection.md).
std::vector<OccupancyGrid> build_empty_space_grids(const TriangleFrames& frames, const ChangeParams& params,
                                                   const VoxelMask& asked, ChangeStats& stats);

/// consistent_with[g * words + (j / 64)] bit (j % 64): triangle g has a consistent partner in
/// acquisition j.
struct PartnerBits {
  std::size_t words = 1;
  std::vector<std::uint64_t> bits;
  [[nodiscard]] bool has(std::size_t g, std::size_t j) const { return (bits[g * words + j / 64] >> (j % 64)) & 1u; }
  /// Triangle g has a partner in some acquisition.
  [[nodiscard]] bool any(std::size_t g) const {
    for (std::size_t w = 0; w < words; ++w) {
      if (bits[g * words + w] != 0) return true;
    }
    return false;
  }
};
PartnerBits partner_bits(const TriangleFrames& frames, const PackedPairs& pairs);

struct ConflictFlags {
  std::vector<std::uint8_t> conflicting;  ///< per global triangle
  std::vector<std::uint8_t> refutes;
};

/// How the conflict search indexes an acquisition's empty spaces: as measured on a sample of
/// the candidates (what detect_changes does), always whole, or always cut into slabs (tests
/// of both indexes).
enum class SlabCut : std::uint8_t { measured, never, always };

/// A triangle conflicts with a newer acquisition j it is not consistent with when it meets
/// the margin-reduced empty space of one of j's triangles (exact triangle-tetrahedron test).
/// Candidates: a box tree's collision between the triangles and j's empty spaces (whole, or
/// cut into slabs of a few metres; only those near some candidate); with the pre-filter,
/// triangles whose box meets no voxel of j's grid are not tested at all. The flags do not
/// depend on `cut`.
ConflictFlags find_conflicts(const TriangleFrames& frames, const PartnerBits& partners,
                             std::span<const OccupancyGrid> grids, const ChangeParams& params, ChangeStats& stats,
                             SlabCut cut = SlabCut::measured);

}  // namespace citymesh::change_detail
