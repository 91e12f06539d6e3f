// SPDX-License-Identifier: MIT
// Shared inside the mosaic module.
#pragma once

#include <cstddef>
#include <vector>

#include "citymesh/core/geometry.h"
#include "citymesh/mosaic/mosaic.h"

namespace citymesh::mosaic_detail {

/// Throws ProcessingError when the change result does not describe the meshes.
void check_mosaic_input(const MosaicInput& input);

/// Acquisition indices by date (config order on equal dates). Wherever the order of the
/// acquisitions matters (the update model, the hole fill, the group moves), it is this one, so
/// that where a pass is listed in the config (a late delivery appended after newer passes)
/// does not change what is selected.
std::vector<std::size_t> date_order(const MosaicInput& input);

/// Whether p lies within `reach` of triangle q's plane and projects inside it (edges
/// included): p is on q, not merely beside it.
bool lies_over(const Vec3d& p, const TriangleCorners& q, double reach);

}  // namespace citymesh::mosaic_detail
