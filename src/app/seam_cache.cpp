// SPDX-License-Identifier: MIT
#include "seam_cache.h"

#include <fmt/format.h>

#include <cstring>
#include <fstream>

#include "citymesh/core/atomic_file.h"
#include "citymesh/core/checksum.h"
#include "citymesh/core/error.h"
#include "citymesh/core/log.h"
#include "citymesh/core/read_file.h"
#include "json_bits.h"
#include "run_state.h"
#include "seam_parts.h"
#include "tiled_run.h"

namespace citymesh::app {

namespace {

constexpr std::string_view kCacheMagic = "CMSTCH01";
constexpr std::string_view kCacheSuffix = ".part";

/// What precedes a kept part: the outcome's JSON and the piece follow, in that order.
struct CacheHeader {
  char magic[8];
  std::uint64_t json_bytes;
  std::uint64_t checksum;  ///< XXH3 of everything after the header
};
static_assert(sizeof(CacheHeader) == 24);

/// The outcome and the piece of a kept part's bytes; nullopt (with the reason) when they are
/// not one SeamPartCache::keep() wrote whole.
std::optional<std::pair<KeyedPiece, PartOutcome>> decode_kept(std::string_view bytes, const std::string& source) {
  CacheHeader h{};
  const auto refuse = [&](std::string_view why) -> std::optional<std::pair<KeyedPiece, PartOutcome>> {
    log::warn("{}: a stitched part of an earlier run, but {}: it is stitched again", source, why);
    return std::nullopt;
  };
  if (bytes.size() < sizeof(h)) return refuse("too short");
  std::memcpy(&h, bytes.data(), sizeof(h));
  if (std::string_view(h.magic, sizeof(h.magic)) != kCacheMagic) return refuse("another magic");
  const std::string_view rest = bytes.substr(sizeof(h));
  if (bulk_checksum(rest.data(), rest.size()) != h.checksum) return refuse("its checksum does not match");
  if (h.json_bytes > rest.size()) return refuse("its counts disagree with its size");
  try {
    PartOutcome outcome = outcome_from(nlohmann::json::parse(rest.substr(0, h.json_bytes)));
    KeyedPiece piece = decode_keyed_piece(rest.substr(h.json_bytes), source);
    return std::pair(std::move(piece), outcome);
  } catch (const std::exception& e) {
    return refuse(e.what());
  }
}

}  // namespace

std::filesystem::path seam_cache_folder(const std::filesystem::path& work) { return work / "seam-cache"; }

nlohmann::json outcome_json(const PartOutcome& o) {
  const StitchStats& s = o.stats;
  return {{"counts",
           {s.vertices_snapped, s.edges_split, s.triangles_uncovered, s.triangles_clipped, s.strips, s.triangles_added,
            s.vertices_welded, s.gaps_filled, s.rejected}},
          {"box", box_bits(o.box)},
          {"cut_triangles", o.cut_triangles},
          {"digest", o.digest},
          {"reused", o.reused}};
}

PartOutcome outcome_from(const nlohmann::json& j) {
  PartOutcome o;
  const auto counts = j.at("counts").get<std::vector<std::uint64_t>>();
  if (counts.size() != 9) throw ProcessingError("a seam part's outcome: counts missing");
  StitchStats& s = o.stats;
  s.vertices_snapped = counts[0], s.edges_split = counts[1], s.triangles_uncovered = counts[2];
  s.triangles_clipped = counts[3], s.strips = counts[4], s.triangles_added = counts[5];
  s.vertices_welded = counts[6], s.gaps_filled = counts[7], s.rejected = counts[8];
  o.box = box_from_bits(j.at("box"));
  o.cut_triangles = j.at("cut_triangles").get<std::size_t>();
  o.digest = j.at("digest").get<std::uint64_t>();
  o.reused = j.at("reused").get<bool>();
  return o;
}

SeamPartCache::SeamPartCache(std::filesystem::path dir, std::uint64_t settings)
    : dir_(std::move(dir)), settings_(settings) {}

std::filesystem::path SeamPartCache::file(const BlockPartKey& key, std::uint64_t digest) const {
  // The build too: another build's stitching may give other parts.
  const std::uint64_t mixed[3] = {settings_, executable_identity(), digest};
  return dir_ / fmt::format("{}.{:016x}{}", key.name(), bulk_checksum(mixed, sizeof(mixed)), kCacheSuffix);
}

std::optional<std::pair<KeyedPiece, PartOutcome>> SeamPartCache::find(const BlockPartKey& key,
                                                                      std::uint64_t digest) const {
  const std::filesystem::path path = file(key, digest);
  const std::optional<std::string> bytes = read_file_bytes(path);
  if (!bytes) return std::nullopt;
  return decode_kept(*bytes, path.string());
}

void SeamPartCache::keep(const BlockPartKey& key, const KeyedPiece& stitched, const PartOutcome& outcome) {
  const std::string json = outcome_json(outcome).dump();
  const std::string piece = encode_keyed_piece(stitched);
  CacheHeader h{};
  std::memcpy(h.magic, kCacheMagic.data(), sizeof(h.magic));
  h.json_bytes = json.size();
  BulkChecksum sum;
  sum.add(json.data(), json.size());
  sum.add(piece.data(), piece.size());
  h.checksum = sum.value();
  std::error_code ec;
  std::filesystem::create_directories(dir_, ec);
  const std::filesystem::path path = file(key, outcome.digest);
  // Under a temporary name first, so that nothing reads a file being written; a run killed
  // here leaves it for the next run's leftover sweep.
  std::filesystem::path temp = path;
  temp += std::string(kTemporaryInfix) + process_tag();
  {
    std::ofstream out(temp, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(&h), sizeof(h));
    out.write(json.data(), static_cast<std::streamsize>(json.size()));
    out.write(piece.data(), static_cast<std::streamsize>(piece.size()));
    if (!out.flush()) {
      log::warn("{}: cannot keep a stitched part for the next run", temp.string());
      out.close();
      std::filesystem::remove(temp, ec);
      return;
    }
  }
  std::filesystem::rename(temp, path, ec);
  if (ec) log::warn("{}: cannot keep a stitched part for the next run: {}", path.string(), ec.message());
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
