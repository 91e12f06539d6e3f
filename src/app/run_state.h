// SPDX-License-Identifier: MIT
// The work folder's record of the config it was made with.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <string>

#include "citymesh/core/checksum.h"

namespace citymesh::app {

inline constexpr const char* kRunConfigFile = "run-config.json";
/// Bumped whenever what the tiler stores or what a tile result means changes.
inline constexpr int kTileStoreVersion = 4;  // 2: one folder per acquisition; 3: XXH3 checksums;
                                             // 4: zero-area triangles dropped as whole-mesh reading drops them
inline constexpr int kTileResultVersion = 3;  // 3: XXH3 checksum

/// A hash of the result-affecting keys (tiling_only: those that change the tile store).
std::uint64_t fingerprint(const std::map<std::string, std::string>& keys, bool tiling_only);

/// Compares `keys` with <work>/run-config.json. When they differ: throws ConfigError naming
/// every changed key, unless `force`. Then records `keys` there.
void check_run_config(const std::filesystem::path& work, const std::map<std::string, std::string>& keys, bool force);

}  // namespace citymesh::app
