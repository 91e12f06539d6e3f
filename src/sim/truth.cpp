// SPDX-License-Identifier: MIT
// Ground-truth sidecar files and object fates.
#include <fmt/format.h>

#include <fstream>

#include "citymesh/core/record_file.h"
#include "citymesh/core/error.h"
#include <nlohmann/json.hpp>

#include "citymesh/sim/scanner.h"
#include "citymesh/sim/simulate.h"

namespace citymesh {

namespace {
constexpr std::string_view kMagic = "CMTRUTH1";
}  // namespace

std::string_view fate_name(Fate f) {
  switch (f) {
    case Fate::keep: return "keep";
    case Fate::remove: return "remove";
    case Fate::unconfirmed: return "unconfirmed";
  }
  return "?";
}

Fate fate_of(const SceneObject& object, const std::vector<EpochDrive>& epochs, Duration sustainability) {
  if (epochs.empty() || !object.present_at(epochs.back().date)) return Fate::remove;
  for (const EpochDrive& e : epochs) {
    if (object.present_at(e.date)) {
      return epochs.back().date - e.date >= sustainability ? Fate::keep : Fate::unconfirmed;
    }
  }
  return Fate::unconfirmed;
}

void write_truth(const std::filesystem::path& path, std::span<const std::uint32_t> ids) {
  write_u32_records(path, kMagic, ids);
}

std::vector<std::uint32_t> read_truth(const std::filesystem::path& path) {
  return read_u32_records(path, kMagic, "ground truth");
}

std::vector<ObjectRecord> read_objects(const std::filesystem::path& sim) {
  const std::filesystem::path file = sim / "objects.json";
  std::ifstream in(file);
  if (!in) throw InputError(fmt::format("{}: cannot open (is {} a citymesh simulate folder?)", file.string(), sim.string()));
  std::vector<ObjectRecord> records;
  try {
    const nlohmann::json j = nlohmann::json::parse(in);  // named: iterating a temporary's member dangles
    for (const auto& o : j.at("objects")) {
      records.push_back({o.at("id").get<std::uint32_t>(), o.at("class").get<std::string>(), o.at("fate").get<std::string>()});
    }
  } catch (const nlohmann::json::exception& e) {
    throw InputError(fmt::format("{}: {}", file.string(), e.what()));
  }
  // Faces lying on no scene surface (bridging a depth jump) are labelled kNoSurface.
  records.push_back({kNoSurface, "no_surface", "none"});
  return records;
}

}  // namespace citymesh
