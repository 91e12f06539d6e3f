// SPDX-License-Identifier: MIT
// Parameters of change detection and the time series ([change] in the config).
#pragma once

#include <chrono>
#include <string_view>

#include "citymesh/core/time.h"

namespace citymesh {

/// What happens to a triangle that is neither conflicting nor sustainable ("unconfirmed":
/// seen once because everything else was occluded or out of range, or first seen less than Ts
/// before the newest acquisition).
enum class UnconfirmedPolicy {
  /// The paper's strict rule: only sustainable triangles are kept.
  drop,
  /// Kept unless a newer acquisition looked at its place (its empty space reaches the
  /// triangle's voxels) and still did not confirm it: absence of confirmation is then
  /// evidence, otherwise it is only occlusion or coverage.
  keep_unobserved,
  /// Every triangle that is not conflicting is kept.
  keep,
};

/// How far a triangle's empty space reaches towards and beyond its surface ([change]
/// empty_space).
enum class EmptySpaceReach {
  /// The paper: the whole tetrahedron between the triangle and its viewpoint, less the points
  /// within conflict_margin of the triangle's plane.
  tetrahedron,
  /// Also no farther from the viewpoint than the triangle's nearest corner, less the margin.
  /// Between two rays the scene may come nearer than the facet joining their samples (the lip
  /// of a cornice between a sample on its underside and the next one on the wall above):
  /// only the depth that every corner's ray reached is claimed empty.
  nearest_sample,
};

struct ChangeParams {
  double distance_threshold = 0.10;  ///< metres: closer surfaces are the same surface
  double conflict_margin = 0.10;     ///< metres: depth into a newer empty space needed to conflict
  EmptySpaceReach empty_space = EmptySpaceReach::tetrahedron;  ///< how far an empty space reaches
  double normal_angle = 45.0;                                  ///< degrees between normals of consistent triangles
  Duration sustainability = std::chrono::days(30);             ///< Ts
  UnconfirmedPolicy unconfirmed = UnconfirmedPolicy::keep_unobserved;
  double voxel_size = 0.5;  ///< metres: the empty-space grids of the pre-filter and the policy
  bool prefilter = true;    ///< skip exact tests where the grids show no newer empty space
};

[[nodiscard]] std::string_view unconfirmed_policy_name(UnconfirmedPolicy p);
[[nodiscard]] std::string_view empty_space_reach_name(EmptySpaceReach r);

}  // namespace citymesh
