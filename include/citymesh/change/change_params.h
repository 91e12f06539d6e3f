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

struct ChangeParams {
  double distance_threshold = 0.10;                 ///< metres: closer surfaces are the same surface
  double conflict_margin = 0.10;                    ///< metres: depth into a newer empty space needed to conflict
  double normal_angle = 45.0;                       ///< degrees between normals of consistent triangles
  Duration sustainability = std::chrono::days(30);  ///< Ts
  UnconfirmedPolicy unconfirmed = UnconfirmedPolicy::keep_unobserved;
  double voxel_size = 0.5;  ///< metres: the empty-space grids of the pre-filter and the policy
  bool prefilter = true;    ///< skip exact tests where the grids show no newer empty space
};

[[nodiscard]] std::string_view unconfirmed_policy_name(UnconfirmedPolicy p);

}  // namespace citymesh
