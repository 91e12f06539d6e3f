// SPDX-License-Identifier: MIT
// The mesh mosaic (paper §IV): among the triangles the change step kept, a non-overlapping
// set that keeps the best pieces of every acquisition with short seams, as the minimum of
//   E(x) = -l1 sum Q(T) x_T + l2 sum L_b(T) x_T + l3 sum_(T,U) consistent x_T x_U
//          + l4 sum_(T,U) same mesh, shared edge L(T,U) XOR(x_T, x_U)
// and the paper's baseline "update model", on one in-memory set of meshes with global ids.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "citymesh/change/detect.h"
#include "citymesh/core/mesh.h"
#include "citymesh/mosaic/binary_energy.h"
#include "citymesh/mosaic/mosaic_params.h"

namespace citymesh {

struct MosaicInput {
  std::span<const Mesh> meshes;  ///< the change step's input: same local origin, global ids
  std::span<const TimePoint> dates;
  const ChangeResult* change = nullptr;
  double distance_threshold = 0.10;  ///< the change step's, for the update model
  /// Per global triangle, 1 when it must be selected (a decision already taken elsewhere: a
  /// neighbouring tile's); empty: none. Forced triangles must be kept.
  std::span<const std::uint8_t> forced;
  /// Solve with the least memory: the group moves' slabs one after another (GroupMoveParams::
  /// slabs_at_once), for a tile that runs alone past the budget. The same selection.
  bool least_memory = false;
};

struct MosaicStats {
  std::uint64_t candidates = 0;  ///< triangles the change step kept: the variables
  std::uint64_t overlap_terms = 0, seam_terms = 0, selected = 0;
  double length_unit = 0;  ///< metres: the mean edge length of the candidates
  /// Weighted energy terms of the selection (the quality term is negative).
  double quality = 0, boundary = 0, overlap = 0, seam = 0, energy = 0;
  std::uint64_t seen_through = 0;       ///< candidates another pass saw through (quality scaled down)
  std::uint64_t filled = 0;             ///< triangles added by the hole fill
  std::uint64_t fill_seen_through = 0;  ///< triangles the hole fill left out: another pass saw through them
  std::uint64_t layers_dropped = 0;     ///< selected triangles dropped as a second layer of their pass
  MinimiseStats solver;                 ///< solver.exact: the whole energy was solved by one flipped cut
  GroupMoveStats moves;                 ///< otherwise: the group moves (one group per acquisition)
  double seconds_build = 0, seconds_solve = 0, seconds_fill = 0;
};

/// Bits of MosaicSelection::notes: what the mosaic found out about a triangle on the way, so
/// that a tiled run can count its owned triangles and the counts add up over tiles.
enum MosaicNote : std::uint8_t {
  kNoteSeenThrough = 1,  ///< a candidate another pass saw through (MosaicStats::seen_through)
  kNoteFilled = 2,       ///< added by the hole fill (MosaicStats::filled)
  kNoteFillLeftOut = 4,  ///< left out by the hole fill: seen through (MosaicStats::fill_seen_through)
};

struct MosaicSelection {
  std::vector<std::uint8_t> selected;  ///< per global triangle
  /// Per global triangle: MosaicNote bits; their counts are the stats' (energy mosaic; empty
  /// for the update model, which notes nothing).
  std::vector<std::uint8_t> notes;
  MosaicStats stats;
};

/// The energy of the candidates (variables in global-id order of the kept triangles) and the
/// global id of each variable.
struct MosaicEnergy {
  BinaryEnergy energy;                     ///< pairs: the seam terms first, then the overlap terms
  std::vector<std::uint32_t> triangle_of;  ///< variable -> global triangle
  std::vector<double> quality, boundary;   ///< per variable: its weighted unary parts
  /// Per variable: its centroid along the scene's longer horizontal extent (where the group
  /// moves cut their slabs).
  std::vector<float> coordinate;
  /// Per variable: 1 when another pass saw through it (seen_through_quality); empty when the
  /// check was not asked (seen_through_quality = 1).
  std::vector<std::uint8_t> seen_through;
  MosaicStats stats;  ///< counts and length unit
};
MosaicEnergy build_mosaic_energy(const MosaicInput& input, const MosaicParams& params);

/// Minimises the mosaic energy: one exact cut when it can be flipped submodular (two meshes),
/// else group moves per acquisition, oldest first whatever the config's listing, from an
/// empty selection (sweeps sweeps at most); then fills holes (fill_holes) when
/// params.fill_holes. Deterministic.
MosaicSelection select_mosaic(const MosaicInput& input, const MosaicParams& params);

/// The baseline: acquisitions in date order (config order on equal dates); a kept triangle is
/// selected unless an already selected triangle of an earlier acquisition lies within the
/// distance threshold of its centroid.
MosaicSelection select_update_model(const MosaicInput& input);

struct HoleFillCounts {
  std::uint64_t added = 0;
  std::uint64_t seen_through = 0;  ///< left out: another pass saw through them
};

/// One layer per pass: for each pair (g, u), g < u, of the change step's layer_pairs
/// (overlapping triangles of one acquisition sharing no corner, such as two turns of a
/// spinning scanner), in the list's order, whose both triangles are selected, u is dropped
/// (g when u is forced in `input`; neither when both are) if its centroid lies on the other
/// (within the distance threshold of its plane, projecting inside it; otherwise it reaches
/// past the other's edge and both stay). `selected[i]` is global triangle base + i. Returns
/// how many were dropped.
std::uint64_t keep_one_layer(const MosaicInput& input, std::size_t base, std::span<std::uint8_t> selected);

/// Hole fill after the energy mosaic: the acquisitions newest first; a kept triangle is added
/// to `selected` when no selected triangle lies within the distance threshold of its centroid
/// (the update model's rule, from the mosaic's selection) and no other pass saw through its
/// centroid (it lies in the empty space of another mesh's triangle, more than the threshold
/// and at most 1 m in front of it; meshes without sensor positions see nothing). Where the
/// mosaic's pieces leave a gap wider than the threshold (a piece's edge falls short of its
/// neighbour's), this puts the input surface back. `seen_through`, per global triangle, gives
/// that check's answers when they are already known (the energy's, same margin and depth);
/// empty: they are worked out for the triangles the fill would add. `notes`, when given (per
/// global triangle), gets kNoteFilled and kNoteFillLeftOut raised where they apply.
HoleFillCounts fill_holes(const MosaicInput& input, std::vector<std::uint8_t>& selected,
                          std::span<const std::uint8_t> seen_through = {}, std::vector<std::uint8_t>* notes = nullptr);

}  // namespace citymesh
