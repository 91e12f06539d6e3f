// SPDX-License-Identifier: MIT
// Shared inside the mosaic module.
#pragma once

#include "citymesh/mosaic/mosaic.h"

namespace citymesh::mosaic_detail {

/// Throws ProcessingError when the change result does not describe the meshes.
void check_mosaic_input(const MosaicInput& input);

}  // namespace citymesh::mosaic_detail
