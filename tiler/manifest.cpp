// SPDX-License-Identifier: MIT
// The tile store's manifest: written last, so a store without one is unfinished.
#include <fmt/format.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>

#include "citymesh/core/atomic_file.h"
#include "citymesh/core/checksum.h"
#include "citymesh/core/error.h"
#include "citymesh/core/log.h"
#include "citymesh/tiler/tiler.h"
#include "store_files.h"

namespace citymesh {

namespace {
constexpr int kManifestVersion = 3;  // 2: one block file per acquisition; 3: checksummed
constexpr const char* kManifestFile = "manifest.json";
constexpr const char* kSummaryFile = "summary.json";
constexpr int kSummaryVersion = 3;  // 3: checksummed, as the manifest

/// The XXH3 of a manifest's or summary's content (every member but "checksum", as compact JSON; members
/// are sorted and numbers written to round-trip, so parsing and dumping again gives the same
/// text), in hex.
std::string content_checksum(nlohmann::json j) {
  j.erase("checksum");
  const std::string text = j.dump();
  return fmt::format("{:016x}", bulk_checksum(text.data(), text.size()));
}

/// Adds the "checksum" member to a manifest or summary about to be written.
void stamp_checksum(nlohmann::json& j) { j["checksum"] = content_checksum(j); }

/// Whether a manifest or summary read back holds its content's checksum: one damaged since it
/// was written, even one that still parses, does not.
bool checksum_matches(const nlohmann::json& j) {
  return j.contains("checksum") && j.at("checksum") == content_checksum(j);
}

nlohmann::json stats_json(const TilingStats& s) {
  return {{"input_bytes", s.input_bytes},
          {"halo_copies", s.halo_copies},
          {"empty_space_copies", s.empty_space_copies},
          {"blocks", s.blocks},
          {"bytes_written", s.bytes_written},
          {"seconds", s.seconds},
          {"largest_radius", s.largest_radius}};
}

TilingStats stats_from_json(const nlohmann::json& s) {
  // largest_radius came later: a store tiled before says nothing of it (0).
  return {s.at("input_bytes").get<std::uint64_t>(),
          s.at("halo_copies").get<std::uint64_t>(),
          s.at("empty_space_copies").get<std::uint64_t>(),
          s.at("blocks").get<std::uint64_t>(),
          s.at("bytes_written").get<std::uint64_t>(),
          s.at("seconds").get<double>(),
          s.value("largest_radius", 0.0)};
}

/// Byte ranges as a flat list: offset, bytes, offset, bytes...
nlohmann::json ranges_json(const std::vector<ByteRange>& ranges) {
  nlohmann::json flat = nlohmann::json::array();
  for (const ByteRange& r : ranges) {
    flat.push_back(r.offset);
    flat.push_back(r.bytes);
  }
  return flat;
}

std::vector<ByteRange> ranges_from_json(const nlohmann::json& flat) {
  const auto numbers = flat.get<std::vector<std::uint64_t>>();
  if (numbers.size() % 2 != 0) throw std::invalid_argument("a block list of odd length");
  std::vector<ByteRange> ranges;
  for (std::size_t k = 0; k < numbers.size(); k += 2) ranges.push_back({numbers[k], numbers[k + 1]});
  return ranges;
}

/// The summary in `folder` when it is finished and made with `fingerprint`.
std::optional<AcquisitionTiling> read_summary(const std::filesystem::path& folder, const std::string& fingerprint) {
  std::ifstream in(folder / kSummaryFile);
  if (!in) return std::nullopt;
  try {
    const nlohmann::json j = nlohmann::json::parse(in);
    if (j.at("version").get<int>() != kSummaryVersion || j.at("fingerprint").get<std::string>() != fingerprint) {
      return std::nullopt;
    }
    // Its block ranges go into the manifest: damage that still parses would misdirect them.
    if (!checksum_matches(j)) throw std::runtime_error("its checksum does not match");
    AcquisitionTiling t;
    t.fingerprint = fingerprint;
    t.triangles = j.at("triangles").get<std::uint64_t>();
    t.stats = stats_from_json(j.at("stats"));
    for (const auto& row : j.at("tiles")) {
      const TileKey key{row.at("i").get<std::int32_t>(), row.at("j").get<std::int32_t>()};
      t.tiles[key] = {row.at("triangles").get<std::array<std::uint64_t, 3>>(), ranges_from_json(row.at("blocks"))};
    }
    return t;
  } catch (const std::exception& e) {
    // Written atomically, so only a damaged file gets here: the acquisition is tiled again.
    log::warn("{}: unreadable ({}): tiled again", (folder / kSummaryFile).string(), e.what());
    return std::nullopt;
  }
}

/// k for a folder named "a<k>" (1 to 9 digits), nothing for any other name.
std::optional<std::size_t> acquisition_folder_index(const std::string& name) {
  if (name.size() < 2 || name.size() > 10 || name[0] != 'a') return std::nullopt;
  std::size_t k = 0;
  for (std::size_t c = 1; c < name.size(); ++c) {
    if (name[c] < '0' || name[c] > '9') return std::nullopt;
    k = k * 10 + static_cast<std::size_t>(name[c] - '0');
  }
  return k;
}

/// Whether the manifest in `dir` is readable, of this build's version and made with
/// `fingerprint` (read_tile_manifest() has said what it thinks of it already).
bool manifest_made_with(const std::filesystem::path& dir, const std::string& fingerprint) {
  std::ifstream in(dir / kManifestFile);
  try {
    const nlohmann::json j = nlohmann::json::parse(in);
    return j.at("version").get<int>() == kManifestVersion && j.at("fingerprint").get<std::string>() == fingerprint;
  } catch (const nlohmann::json::exception&) {
    return false;
  }
}

}  // namespace

void write_acquisition_tiling(const std::filesystem::path& dir, const AcquisitionTiling& tiling) {
  nlohmann::json tiles = nlohmann::json::array();
  for (const auto& [key, t] : tiling.tiles) {
    tiles.push_back({{"i", key.i}, {"j", key.j}, {"triangles", t.counts}, {"blocks", ranges_json(t.blocks)}});
  }
  nlohmann::json j{{"version", kSummaryVersion},
                   {"fingerprint", tiling.fingerprint},
                   {"triangles", tiling.triangles},
                   {"stats", stats_json(tiling.stats)},
                   {"tiles", std::move(tiles)}};
  stamp_checksum(j);
  write_file_atomically(dir / kSummaryFile, j.dump() + "\n");
}

std::optional<AcquisitionTiling> read_acquisition_tiling(const std::filesystem::path& dir, std::uint32_t acquisition,
                                                         const std::string& fingerprint) {
  return read_summary(acquisition_tiles_path(dir, acquisition), fingerprint);
}

std::optional<AcquisitionTiling> publish_acquisition_tiling(const std::filesystem::path& staged,
                                                            const std::filesystem::path& target,
                                                            const std::string& fingerprint) {
  if (std::rename(staged.c_str(), target.c_str()) == 0) {
    sync_directory(target.parent_path());
    return std::nullopt;
  }
  if (errno != EEXIST && errno != ENOTEMPTY) {
    throw OutputError(
        fmt::format("{}: cannot rename the tiled acquisition into place: {}", target.string(), std::strerror(errno)));
  }
  if (std::optional<AcquisitionTiling> first = read_summary(target, fingerprint)) {
    std::error_code ec;
    std::filesystem::remove_all(staged, ec);
    return first;
  }
  replace_directory_atomically(staged, target);
  return std::nullopt;
}

namespace {

/// The fingerprint the summary in `folder` was made with, when it is of this version (the
/// rest is checked by read_summary when the folder is used).
std::optional<std::string> summary_fingerprint(const std::filesystem::path& folder) {
  std::ifstream in(folder / kSummaryFile);
  if (!in) return std::nullopt;
  try {
    const nlohmann::json j = nlohmann::json::parse(in);
    if (j.at("version").get<int>() != kSummaryVersion) return std::nullopt;
    return j.at("fingerprint").get<std::string>();
  } catch (const nlohmann::json::exception&) {
    return std::nullopt;
  }
}

}  // namespace

std::size_t move_renumbered_tilings(const std::filesystem::path& dir,
                                    std::span<const std::string> acquisition_fingerprints) {
  std::map<std::size_t, std::string> held;  // per acquisition folder, its fingerprint
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(dir, ec)) {
    const std::optional<std::size_t> k = acquisition_folder_index(entry.path().filename().string());
    if (!k) continue;
    if (std::optional<std::string> f = summary_fingerprint(entry.path())) held.emplace(*k, std::move(*f));
  }
  std::vector<std::pair<std::size_t, std::size_t>> moves;  // from folder, to folder
  for (std::size_t k = 0; k < acquisition_fingerprints.size(); ++k) {
    const auto own = held.find(k);
    if (own != held.end() && own->second == acquisition_fingerprints[k]) continue;
    // A folder holding its own acquisition's tiling stays; one moved goes once.
    const auto in_place = [&](std::size_t j, const std::string& f) {
      return j < acquisition_fingerprints.size() && acquisition_fingerprints[j] == f;
    };
    const auto from = std::find_if(held.begin(), held.end(), [&](const auto& h) {
      return h.second == acquisition_fingerprints[k] && !in_place(h.first, h.second);
    });
    if (from == held.end()) continue;
    moves.emplace_back(from->first, k);
    held.erase(from);
  }
  if (moves.empty()) return 0;
  // Every folder is moved aside before any is put in place: a folder may be the source of one
  // move and the target of another. A run killed between the two leaves them in staging,
  // which the next run removes (those acquisitions are then tiled again).
  const std::filesystem::path staging = dir / kStagingFolder;
  std::filesystem::create_directories(staging, ec);
  std::vector<std::filesystem::path> aside;
  for (const auto& [from, to] : moves) {
    const std::filesystem::path source = acquisition_tiles_path(dir, static_cast<std::uint32_t>(from));
    aside.push_back(staging / fmt::format("renumbered.a{}.{}", to, process_tag()));
    if (std::rename(source.c_str(), aside.back().c_str()) != 0) {
      throw OutputError(
          fmt::format("{}: cannot move the tiled acquisition aside: {}", source.string(), std::strerror(errno)));
    }
  }
  for (std::size_t m = 0; m < moves.size(); ++m) {
    replace_directory_atomically(aside[m], acquisition_tiles_path(dir, static_cast<std::uint32_t>(moves[m].second)));
  }
  return moves.size();
}

void prune_tile_store(const std::filesystem::path& dir, std::span<const std::string> acquisition_fingerprints,
                      const std::string& store_fingerprint, bool staging) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw OutputError(fmt::format("{}: cannot create the tile store: {}", dir.string(), ec.message()));
  std::vector<std::filesystem::path> stale;
  for (const auto& entry : std::filesystem::directory_iterator(dir, ec)) {
    const std::string name = entry.path().filename().string();
    if (name == kStagingFolder) {
      if (staging) stale.push_back(entry.path());
    } else if (const std::optional<std::size_t> k = acquisition_folder_index(name);
               k && *k < acquisition_fingerprints.size()) {
      if (!read_summary(entry.path(), acquisition_fingerprints[*k])) stale.push_back(entry.path());
    } else if (name == kManifestFile) {
      if (!manifest_made_with(dir, store_fingerprint)) stale.push_back(entry.path());
    } else {
      stale.push_back(entry.path());  // a store of an older layout, or a dropped acquisition
    }
  }
  for (const auto& path : stale) {
    std::filesystem::remove_all(path, ec);
    if (ec) throw OutputError(fmt::format("{}: cannot remove stale tiling work: {}", path.string(), ec.message()));
  }
}

void write_tile_manifest(const TileStore& store) {
  nlohmann::json j;
  j["version"] = kManifestVersion;
  j["fingerprint"] = store.fingerprint;
  j["grid"] = {{"tile_size", store.grid.tile_size}, {"halo", store.grid.halo}, {"origin", store.grid.origin}};
  j["triangles"] = store.triangles;
  j["stats"] = stats_json(store.stats);
  nlohmann::json tiles = nlohmann::json::array();
  for (const TileContents& t : store.tiles) {
    nlohmann::json blocks = nlohmann::json::array();
    for (const std::vector<ByteRange>& ranges : t.blocks) blocks.push_back(ranges_json(ranges));
    tiles.push_back({{"i", t.key.i}, {"j", t.key.j}, {"triangles", t.triangles}, {"blocks", std::move(blocks)}});
  }
  j["tiles"] = std::move(tiles);
  stamp_checksum(j);
  write_file_atomically(store.dir / kManifestFile, j.dump(1) + "\n");
}

std::optional<TileStore> read_tile_manifest(const std::filesystem::path& dir) {
  const std::filesystem::path file = dir / kManifestFile;
  std::ifstream in(file);
  if (!in) return std::nullopt;
  try {
    const nlohmann::json j = nlohmann::json::parse(in);
    const int version = j.at("version").get<int>();
    if (version < kManifestVersion) {
      // An older build's layout: not this build's finished store, so it is tiled again.
      log::info("{}: a tile store of version {} (this build writes {}): tiled again", file.string(), version,
                kManifestVersion);
      return std::nullopt;
    }
    if (version != kManifestVersion) {
      throw InputError(
          fmt::format("{}: manifest version {} (this build writes {}); delete the work folder or run "
                      "with --force",
                      file.string(), j.at("version").dump(), kManifestVersion));
    }
    // Every block is found through it: damage that still parses would read other bytes.
    if (!checksum_matches(j)) {
      log::warn("{}: damaged (its checksum does not match): the tile store is made again", file.string());
      return std::nullopt;
    }
    TileStore store;
    store.dir = dir;
    store.fingerprint = j.at("fingerprint").get<std::string>();
    store.grid.tile_size = j.at("grid").at("tile_size").get<double>();
    store.grid.halo = j.at("grid").at("halo").get<double>();
    store.grid.origin = j.at("grid").at("origin").get<std::array<double, 2>>();
    store.triangles = j.at("triangles").get<std::vector<std::uint64_t>>();
    store.stats = stats_from_json(j.at("stats"));
    for (const auto& t : j.at("tiles")) {
      TileContents c{{t.at("i").get<std::int32_t>(), t.at("j").get<std::int32_t>()},
                     t.at("triangles").get<std::vector<std::array<std::uint64_t, 3>>>(),
                     {}};
      for (const auto& ranges : t.at("blocks")) c.blocks.push_back(ranges_from_json(ranges));
      if (c.triangles.size() != store.triangles.size() || c.blocks.size() != store.triangles.size()) {
        throw InputError(fmt::format("{}: tile {} lists {} acquisitions and {} block lists, the store {} acquisitions",
                                     file.string(), c.key.name(), c.triangles.size(), c.blocks.size(),
                                     store.triangles.size()));
      }
      if (!store.tiles.empty() && !(store.tiles.back().key < c.key)) {
        throw InputError(fmt::format("{}: tile {} is out of order", file.string(), c.key.name()));
      }
      store.tiles.push_back(std::move(c));
    }
    return store;
  } catch (const nlohmann::json::parse_error& e) {
    // Written atomically by citymesh: a file that does not parse was damaged since.
    log::warn("{}: damaged ({}): the tile store is made again", file.string(), e.what());
    return std::nullopt;
  } catch (const nlohmann::json::exception& e) {
    throw InputError(fmt::format("{}: malformed tile manifest: {}", file.string(), e.what()));
  } catch (const std::invalid_argument& e) {
    throw InputError(fmt::format("{}: malformed tile manifest: {}", file.string(), e.what()));
  }
}

}  // namespace citymesh
