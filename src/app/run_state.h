// SPDX-License-Identifier: MIT
// The work folder's record of the config it was made with.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "citymesh/core/checksum.h"

namespace citymesh::app {

inline constexpr const char* kRunConfigFile = "run-config.json";
/// Bumped whenever what the tiler stores or what a tile result means changes. The tile
/// results also depend on the build (run_fingerprints holds it), the tile store does not:
/// a change to which triangles the tiler puts where must bump kTileStoreVersion.
inline constexpr int kTileStoreVersion = 4;   // 2: one folder per acquisition; 3: XXH3 checksums;
                                              // 4: zero-area triangles dropped as whole-mesh reading drops them
inline constexpr int kTileResultVersion = 5;  // 3: XXH3 checksum; 4: keyed on each tile's own inputs;
                                              // 5: its passes named by identity, not index

/// Hashes of the result-affecting keys, split so that work depending on some acquisitions
/// only is reused when another acquisition is added or rewritten.
struct RunFingerprints {
  /// The keys other than the acquisitions' (and the formats' versions): every tile result
  /// depends on them.
  std::uint64_t settings = 0;
  /// Per acquisition: the keys that change the tile store (input, tiling) and its own keys
  /// without its index (path, file size and time, date...): its tiled folder, found by it
  /// when a pass delivered late renumbers the passes after it (move_renumbered_tilings).
  std::vector<std::uint64_t> acquisitions;
  /// Per acquisition: its own keys without its index (what `acquisitions` holds but the
  /// tiling keys). A pass delivered late renumbers the passes after it by time; their
  /// identities stay, so a tile it does not reach is known to hold the same passes.
  std::vector<std::uint64_t> identities;
  /// The tile store as a whole (its manifest): the tiling keys and every acquisition's.
  std::uint64_t store = 0;
};
/// This build of citymesh as run-config.json and run.json name it, and as the result
/// fingerprint holds it: executable_identity() in hex.
std::string build_name();

RunFingerprints run_fingerprints(const std::map<std::string, std::string>& keys, std::size_t acquisitions);

/// Compares `keys` with <work>/run-config.json. When they differ: throws ConfigError naming
/// every changed key, unless `force`. Acquisitions added after the last one recorded and
/// rewritten input files are not changes: they are logged, and the work they touch is redone.
/// Says when another build of citymesh did the work (its results are made again: the run
/// fingerprint holds the build). Then records `keys` and this build there.
void check_run_config(const std::filesystem::path& work, const std::map<std::string, std::string>& keys, bool force);
/// The same checks and messages, recording nothing: a plan of the run (`run --plan`) leaves
/// the record as the last run made it.
void check_run_config_unrecorded(const std::filesystem::path& work, const std::map<std::string, std::string>& keys,
                                 bool force);

}  // namespace citymesh::app
