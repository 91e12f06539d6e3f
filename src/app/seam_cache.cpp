// SPDX-License-Identifier: MIT
#include "seam_cache.h"

#include <fmt/format.h>

#include "citymesh/core/checksum.h"
#include "citymesh/core/error.h"
#include "citymesh/core/log.h"
#include "json_bits.h"
#include "kept_files.h"
#include "run_state.h"
#include "seam_parts.h"
#include "tiled_run.h"

namespace citymesh::app {

namespace {

// 02: new vertices named by their part's rank; 03: ten counts (the centroid splits)
constexpr std::string_view kCacheMagic = "CMSTCH03";
constexpr std::string_view kCacheSuffix = ".part";

}  // namespace

std::filesystem::path seam_cache_folder(const std::filesystem::path& work) { return work / "seam-cache"; }

nlohmann::json outcome_json(const PartOutcome& o) {
  std::vector<std::uint64_t> counts;
  for (const auto count : kStitchCounts) counts.push_back(o.stats.*count);
  return {{"counts", counts},   {"box", box_bits(o.box)}, {"cut_triangles", o.cut_triangles},
          {"digest", o.digest}, {"reused", o.reused},     {"key_parts", block_part_keys_json(o.key_parts)}};
}

PartOutcome outcome_from(const nlohmann::json& j) {
  PartOutcome o;
  const auto counts = j.at("counts").get<std::vector<std::uint64_t>>();
  if (counts.size() != kStitchCounts.size()) throw ProcessingError("a seam part's outcome: counts missing");
  for (std::size_t k = 0; k < counts.size(); ++k) o.stats.*kStitchCounts[k] = counts[k];
  o.box = box_from_bits(j.at("box"));
  o.cut_triangles = j.at("cut_triangles").get<std::size_t>();
  o.digest = j.at("digest").get<std::uint64_t>();
  o.reused = j.at("reused").get<bool>();
  o.key_parts = block_part_keys_from(j.at("key_parts"));
  return o;
}

SeamPartCache::SeamPartCache(std::filesystem::path dir, std::uint64_t settings)
    : dir_(std::move(dir)), settings_(settings) {}

std::filesystem::path SeamPartCache::file(const BlockPartKey& key, std::uint64_t digest) const {
  // The build is in `settings` (the run's result fingerprint holds it): another build's
  // stitching may give other parts.
  const std::uint64_t mixed[2] = {settings_, digest};
  return dir_ / fmt::format("{}.{:016x}{}", key.name(), bulk_checksum(mixed, sizeof(mixed)), kCacheSuffix);
}

std::optional<std::pair<KeyedPiece, PartOutcome>> SeamPartCache::find(const BlockPartKey& key,
                                                                      std::uint64_t digest) const {
  const std::filesystem::path path = file(key, digest);
  const auto kept = read_kept_file(path, kCacheMagic, "a stitched part");
  if (!kept) return std::nullopt;
  try {
    return std::pair(decode_keyed_piece(kept->second, path.string()), outcome_from(kept->first));
  } catch (const std::exception& e) {
    warn_made_again(path, "a stitched part", e.what());
    return std::nullopt;
  }
}

void SeamPartCache::keep(const BlockPartKey& key, const KeyedPiece& stitched, const PartOutcome& outcome) {
  write_kept_file(file(key, outcome.digest), kCacheMagic, outcome_json(outcome).dump(), encode_keyed_piece(stitched));
}

void SeamPartCache::prune(std::span<const BlockPart> parts, std::span<const std::uint64_t> digests) const {
  std::set<std::string> used;
  for (std::size_t p = 0; p < parts.size() && p < digests.size(); ++p) {
    used.insert(file(parts[p].key, digests[p]).filename().string());
  }
  std::error_code ec;
  std::vector<std::filesystem::path> stale;
  for (const auto& entry : std::filesystem::directory_iterator(dir_, ec)) {
    const std::string name = entry.path().filename().string();
    // Another process's file being written is its own (the leftover sweep takes it if it ended).
    if (name.ends_with(kCacheSuffix) && !used.contains(name)) stale.push_back(entry.path());
  }
  for (const std::filesystem::path& f : stale) std::filesystem::remove(f, ec);
}

SeamPartCache seam_part_cache(const Config& config) {
  return {seam_cache_folder(config.project.work),
          run_fingerprints(result_keys(config), config.acquisitions.size()).settings};
}

}  // namespace citymesh::app
