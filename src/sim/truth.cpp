// SPDX-License-Identifier: MIT
// Ground-truth sidecar files and object fates.
#include <fmt/format.h>

#include <cstring>
#include <fstream>

#include "citymesh/core/atomic_file.h"
#include "citymesh/core/error.h"
#include <nlohmann/json.hpp>

#include "citymesh/sim/scanner.h"
#include "citymesh/sim/simulate.h"

namespace citymesh {

namespace {
constexpr char kMagic[8] = {'C', 'M', 'T', 'R', 'U', 'T', 'H', '1'};

std::uint64_t fnv1a(const void* data, std::size_t size) {
  std::uint64_t h = 0xcbf29ce484222325ull;
  const auto* p = static_cast<const unsigned char*>(data);
  for (std::size_t i = 0; i < size; ++i) h = (h ^ p[i]) * 0x100000001b3ull;
  return h;
}
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
  AtomicFile file(path);
  const std::uint64_t count = ids.size(), sum = fnv1a(ids.data(), ids.size_bytes());
  file.write(kMagic, sizeof kMagic);
  file.write(&count, sizeof count);
  file.write(ids.data(), ids.size_bytes());
  file.write(&sum, sizeof sum);
  file.commit();
}

std::vector<std::uint32_t> read_truth(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(fmt::format("{}: cannot open ground truth", path.string()));
  char magic[8];
  std::uint64_t count = 0, sum = 0;
  if (!in.read(magic, 8) || std::memcmp(magic, kMagic, 8) != 0) {
    throw InputError(fmt::format("{}: not a citymesh ground-truth file", path.string()));
  }
  in.read(reinterpret_cast<char*>(&count), sizeof count);
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  if (!in || ec || size < 24 || (size - 24) % 4 != 0 || count != (size - 24) / 4) {
    throw InputError(fmt::format("{}: ground truth is truncated or its count is wrong", path.string()));
  }
  std::vector<std::uint32_t> ids(count);
  in.read(reinterpret_cast<char*>(ids.data()), static_cast<std::streamsize>(count * 4));
  in.read(reinterpret_cast<char*>(&sum), sizeof sum);
  if (!in || sum != fnv1a(ids.data(), ids.size() * 4)) {
    throw InputError(fmt::format("{}: ground truth checksum mismatch", path.string()));
  }
  return ids;
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
