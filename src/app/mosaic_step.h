// SPDX-License-Identifier: MIT
// The mosaic step `citymesh run` and `citymesh mosaic` share, and how `mosaic` finds the
// change step's result in <output>/detect.
#pragma once

#include <nlohmann/json.hpp>

#include "acquisitions.h"
#include "citymesh/change/detect.h"
#include "citymesh/mosaic/merged_mesh.h"
#include "citymesh/mosaic/stitch_blocks.h"
#include "pipeline.h"

namespace citymesh::app {

class SeamPartCache;

/// Selects (energy or update model), merges, stitches (energy only) and writes
/// <output>/mosaic; `seconds` (earlier steps) goes into its summary. Prints a short report.
void run_mosaic_step(const Config& config, const LoadedAcquisitions& input, const ChangeResult& change,
                     const PictureOptions& pictures, nlohmann::json seconds);

/// Whether a tiled run's seam pass runs block by block (`[run] seam_pass`: "blocks", or "auto"
/// with tiles wide enough for its bands; the energy mosaic only).
bool seam_pass_in_blocks(const Config& config);

/// Throws ConfigError when `[run] seam_pass = "blocks"` and the tiles are too small for its bands.
/// A tiled run checks it first, before hours of tiles, not only when the seam pass starts.
void check_seam_pass(const Config& config);

/// Stitches `merged` at once with the config's reach and weld, prints a line and returns the
/// figures for the summary.
nlohmann::json stitch_and_report(const Config& config, MergedMesh& merged);

/// The tile grid as blocks of block stitching, in the project CRS, bands as narrow as the
/// stitching's reach allows.
BlockStitchParams tile_grid_blocks(const Config& config);

/// Stitching's parameters from `[mosaic]` and the distance threshold.
StitchParams stitch_params(const Config& config);

/// Where the parts of a seam pass by blocks are stitched and measured (unset: on this
/// process's threads; a tiled MPI run shares them with every rank, seam_ranks.h). Before
/// stitching, the open boundary is measured; then the four levels are stitched; then it is
/// measured again: the steps the ranks helping follow.
struct SeamPassWork {
  decltype(PartStitchRun::run_level) run_level;
  MeasureParts measure_parts;
};

/// Stitches the parts in `store` block by block on the tile grid (`[run] seam_pass =
/// "blocks"`), `source_sizes` the output's triangles per source; prints and returns the
/// figures as stitch_and_report does. With `cache`, parts whose inputs are those of a part
/// the cache kept are taken from it, the others kept in it, and the rest of it pruned.
nlohmann::json stitch_parts_and_report(const Config& config, std::vector<BlockPart>& parts, PartStore& store,
                                       std::span<const std::uint64_t> source_sizes, const SeamPassWork& work = {},
                                       SeamPartCache* cache = nullptr);

/// What the mosaic needs of a finished `citymesh detect`: the kept flags (from the labelled
/// PLYs) and the consistent pairs (pairs.bin). Throws InputError naming the file when the
/// detect output is missing, unfinished or does not match the acquisitions. Its summary lists
/// them as the config file does (`config`'s listed indices).
ChangeResult read_detect_result(const std::filesystem::path& dir, const Config& config,
                                const LoadedAcquisitions& input);

}  // namespace citymesh::app
