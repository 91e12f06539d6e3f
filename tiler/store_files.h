// SPDX-License-Identifier: MIT
// The tile store's bookkeeping files, private to the tiler: each acquisition's summary and
// the step that puts a finished acquisition folder in place.
#pragma once

#include <filesystem>
#include <optional>
#include <string>

#include "citymesh/tiler/tiler.h"

namespace citymesh {

/// An acquisition's block file in its folder of the store.
inline constexpr const char* kBlocksFile = "blocks.bin";

/// Writes <dir>/summary.json (atomically).
void write_acquisition_tiling(const std::filesystem::path& dir, const AcquisitionTiling& tiling);

/// Renames the finished folder `staged` to `target`. When another process put a finished copy
/// made with `fingerprint` there first, `staged` is dropped and that copy's summary returned
/// (the tiler is deterministic: same bytes); a stale `target` is swapped out and removed.
std::optional<AcquisitionTiling> publish_acquisition_tiling(const std::filesystem::path& staged,
                                                            const std::filesystem::path& target,
                                                            const std::string& fingerprint);

}  // namespace citymesh
