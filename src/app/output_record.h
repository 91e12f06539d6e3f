// SPDX-License-Identifier: MIT
// What a tiled run's final pass last wrote, kept in <work>/outputs.json: a run that finds
// every tile's result made already and nothing else changed skips its final pass, as make
// skips a target newer than its inputs (a nightly job with no new pass costs a few seconds
// rather than the whole output written again).
#pragma once

#include <cstdint>
#include <filesystem>
#include <span>

#include "citymesh/config/config.h"
#include "pipeline.h"

namespace citymesh::app {

/// <work>/outputs.json.
std::filesystem::path output_record_path(const std::filesystem::path& work);

/// A digest of everything the final pass's outputs are made from: this build, the config
/// file's path and every key of the config (result-affecting or not: output keys, folders,
/// the acquisitions' names and dates), the picture options, and each tile result's inputs
/// digest (a result is a function of its digest: the tile stage checks each result whole).
std::uint64_t final_pass_digest(const Config& config, std::span<const std::uint64_t> result_digests,
                                const PictureOptions& pictures);

/// Removes the record: called before the final pass writes anything, so that a pass killed
/// half way leaves none and the next run writes the outputs again. Throws OutputError when
/// the record exists and cannot be removed.
void forget_outputs(const std::filesystem::path& work);

/// Records `digest` with the files the final pass wrote under the output folder (run.json and
/// every file under detect/, mosaic/, tiles/ and ply/), each with its size and modification
/// time. Best effort: a record not written only means the next run writes the outputs again.
void record_outputs(const Config& config, std::uint64_t digest);

/// Whether the record holds `digest` and every file it lists is still there with its size and
/// modification time (a file removed, rewritten or touched: false). False without a record,
/// and with one that cannot be read.
bool outputs_up_to_date(const Config& config, std::uint64_t digest);

}  // namespace citymesh::app
