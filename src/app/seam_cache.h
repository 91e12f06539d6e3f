// SPDX-License-Identifier: MIT
// The stitched parts of a tiled run's seam pass by blocks, kept in the work folder for the
// next run (a monthly pass appended over one district restitches only the parts near it).
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <span>

#include "citymesh/config/config.h"
#include "citymesh/mosaic/stitch_blocks.h"

namespace citymesh::app {

/// <work>/seam-cache: where SeamPartCache keeps the stitched parts.
std::filesystem::path seam_cache_folder(const std::filesystem::path& work);

/// The counts stitch_parts() adds up, the part's stitched box, its size with surroundings,
/// its digest and whether it was reused: what a rank or the cache hands back for a part.
nlohmann::json outcome_json(const PartOutcome& o);
/// Throws ProcessingError when `j` is not one outcome_json() wrote.
PartOutcome outcome_from(const nlohmann::json& j);

/// A PartCache in one folder, one file per part: "<part>.<digest>.part" (magic, the outcome
/// as JSON, the stitched piece, an XXH3 of both). The digest mixes in `settings` (the run's
/// result fingerprint: its result-affecting keys and the build, run_fingerprints). Files go in under a temporary name
/// and are renamed (no fsync: a torn file fails its checksum and is stitched again, like a missing one). Any process of
/// the run may find and keep parts; the root prunes what the run did not use.
class SeamPartCache final : public PartCache {
 public:
  SeamPartCache(std::filesystem::path dir, std::uint64_t settings);

  [[nodiscard]] std::optional<std::pair<KeyedPiece, PartOutcome>> find(const BlockPartKey& key,
                                                                       std::uint64_t digest) const override;
  void keep(const BlockPartKey& key, const KeyedPiece& stitched, const PartOutcome& outcome) override;

  /// Removes every kept part but part p of `parts` with digest digests[p], for each p: what a
  /// finished run used is all the next one can reuse. Best effort.
  void prune(std::span<const BlockPart> parts, std::span<const std::uint64_t> digests) const;

 private:
  [[nodiscard]] std::filesystem::path file(const BlockPartKey& key, std::uint64_t digest) const;

  std::filesystem::path dir_;
  std::uint64_t settings_;
};

/// The run's cache: in seam_cache_folder(), mixing in the result-affecting keys of `config`
/// other than the acquisitions' (an acquisition appended keeps what it does not reach).
SeamPartCache seam_part_cache(const Config& config);

}  // namespace citymesh::app
