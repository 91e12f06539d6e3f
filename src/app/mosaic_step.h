// SPDX-License-Identifier: MIT
// The mosaic step `citymesh run` and `citymesh mosaic` share, and how `mosaic` finds the
// change step's result in <output>/detect.
#pragma once

#include <nlohmann/json.hpp>

#include "acquisitions.h"
#include "citymesh/change/detect.h"
#include "citymesh/mosaic/merged_mesh.h"
#include "pipeline.h"

namespace citymesh::app {

/// Selects (energy or update model), merges, stitches (energy only) and writes
/// <output>/mosaic; `seconds` (earlier steps) goes into its summary. Prints a short report.
void run_mosaic_step(const Config& config, const LoadedAcquisitions& input, const ChangeResult& change,
                     const PictureOptions& pictures, nlohmann::json seconds);

/// Throws ConfigError when `[run] seam_pass = "blocks"` and the tiles are too small for its bands.
/// A tiled run checks it first, before hours of tiles, not only when the seam pass starts.
void check_seam_pass(const Config& config);

/// Stitches `merged` with the config's reach and weld, prints a line and returns the figures
/// for the summary. `pass`: at once, or block by block on the tile grid (only a tiled run has
/// one: it passes `[run] seam_pass`).
nlohmann::json stitch_and_report(const Config& config, MergedMesh& merged, SeamPass pass = SeamPass::whole);

/// What the mosaic needs of a finished `citymesh detect`: the kept flags (from the labelled
/// PLYs) and the consistent pairs (pairs.bin). Throws InputError naming the file when the
/// detect output is missing, unfinished or does not match the acquisitions.
ChangeResult read_detect_result(const std::filesystem::path& dir, const LoadedAcquisitions& input);

}  // namespace citymesh::app
