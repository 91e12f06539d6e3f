// SPDX-License-Identifier: MIT
// The tile store's manifest: written last, so a store without one is unfinished.
#include <fmt/format.h>

#include <fstream>
#include <nlohmann/json.hpp>

#include "citymesh/core/atomic_file.h"
#include "citymesh/core/error.h"
#include "citymesh/tiler/tiler.h"

namespace citymesh {

namespace {
constexpr int kManifestVersion = 1;
constexpr const char* kManifestFile = "manifest.json";
}  // namespace

void write_tile_manifest(const TileStore& store) {
  nlohmann::json j;
  j["version"] = kManifestVersion;
  j["fingerprint"] = store.fingerprint;
  j["grid"] = {{"tile_size", store.grid.tile_size}, {"halo", store.grid.halo}, {"origin", store.grid.origin}};
  j["triangles"] = store.triangles;
  j["stats"] = {{"input_bytes", store.stats.input_bytes},
                {"halo_copies", store.stats.halo_copies},
                {"empty_space_copies", store.stats.empty_space_copies},
                {"blocks", store.stats.blocks},
                {"bytes_written", store.stats.bytes_written},
                {"seconds", store.stats.seconds}};
  nlohmann::json tiles = nlohmann::json::array();
  for (const TileContents& t : store.tiles) tiles.push_back({{"i", t.key.i}, {"j", t.key.j}, {"triangles", t.triangles}});
  j["tiles"] = std::move(tiles);
  write_file_atomically(store.dir / kManifestFile, j.dump(1) + "\n");
}

std::optional<TileStore> read_tile_manifest(const std::filesystem::path& dir) {
  const std::filesystem::path file = dir / kManifestFile;
  std::ifstream in(file);
  if (!in) return std::nullopt;
  try {
    const nlohmann::json j = nlohmann::json::parse(in);
    if (j.at("version").get<int>() != kManifestVersion) {
      throw InputError(fmt::format("{}: manifest version {} (this build writes {}); delete the work folder or run "
                                   "with --force",
                                   file.string(), j.at("version").dump(), kManifestVersion));
    }
    TileStore store;
    store.dir = dir;
    store.fingerprint = j.at("fingerprint").get<std::string>();
    store.grid.tile_size = j.at("grid").at("tile_size").get<double>();
    store.grid.halo = j.at("grid").at("halo").get<double>();
    store.grid.origin = j.at("grid").at("origin").get<std::array<double, 2>>();
    store.triangles = j.at("triangles").get<std::vector<std::uint64_t>>();
    const auto& s = j.at("stats");
    store.stats = {s.at("input_bytes").get<std::uint64_t>(),  s.at("halo_copies").get<std::uint64_t>(),
                   s.at("empty_space_copies").get<std::uint64_t>(), s.at("blocks").get<std::uint64_t>(),
                   s.at("bytes_written").get<std::uint64_t>(), s.at("seconds").get<double>()};
    for (const auto& t : j.at("tiles")) {
      TileContents c{{t.at("i").get<std::int32_t>(), t.at("j").get<std::int32_t>()},
                     t.at("triangles").get<std::vector<std::array<std::uint64_t, 3>>>()};
      if (c.triangles.size() != store.triangles.size()) {
        throw InputError(fmt::format("{}: tile {} lists {} acquisitions, the store {}", file.string(), c.key.name(),
                                     c.triangles.size(), store.triangles.size()));
      }
      store.tiles.push_back(std::move(c));
    }
    return store;
  } catch (const nlohmann::json::exception& e) {
    throw InputError(fmt::format("{}: malformed tile manifest: {}", file.string(), e.what()));
  }
}

}  // namespace citymesh
