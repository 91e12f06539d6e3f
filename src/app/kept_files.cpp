// SPDX-License-Identifier: MIT
#include "kept_files.h"

#include <fmt/format.h>

#include <chrono>
#include <cstring>
#include <fstream>

#include "citymesh/core/atomic_file.h"
#include "citymesh/core/checksum.h"
#include "citymesh/core/log.h"
#include "citymesh/core/read_file.h"

namespace citymesh::app {

namespace {

/// What precedes a kept file's JSON and bytes.
struct KeptHeader {
  char magic[8];
  std::uint64_t json_bytes;
  std::uint64_t checksum;  ///< XXH3 of everything after the header
};
static_assert(sizeof(KeptHeader) == 24);

}  // namespace

void warn_made_again(const std::filesystem::path& path, std::string_view what, std::string_view why) {
  log::warn("{}: {} of an earlier run, but {}: it is made again", path.string(), what, why);
}

void write_kept_file(const std::filesystem::path& path, std::string_view magic, std::string_view json,
                     std::string_view bytes) {
  KeptHeader h{};
  std::memcpy(h.magic, magic.data(), std::min(magic.size(), sizeof(h.magic)));
  h.json_bytes = json.size();
  BulkChecksum sum;
  sum.add(json.data(), json.size());
  sum.add(bytes.data(), bytes.size());
  h.checksum = sum.value();
  std::error_code ec;
  std::filesystem::create_directories(path.parent_path(), ec);
  // Under a temporary name first, so that nothing reads a file being written; a run killed
  // here leaves it for the next run's leftover sweep.
  std::filesystem::path temp = path;
  temp += std::string(kTemporaryInfix) + process_tag();
  {
    std::ofstream out(temp, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(&h), sizeof(h));
    out.write(json.data(), static_cast<std::streamsize>(json.size()));
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    if (!out.flush()) {
      log::warn("{}: cannot keep it for the next run", temp.string());
      out.close();
      std::filesystem::remove(temp, ec);
      return;
    }
  }
  std::filesystem::rename(temp, path, ec);
  if (ec) log::warn("{}: cannot keep it for the next run: {}", path.string(), ec.message());
}

std::optional<std::pair<nlohmann::json, std::string>> read_kept_file(const std::filesystem::path& path,
                                                                     std::string_view magic, std::string_view what) {
  const std::optional<std::string> bytes = read_file_bytes(path);
  if (!bytes) return std::nullopt;
  const auto refuse = [&](std::string_view why) -> std::optional<std::pair<nlohmann::json, std::string>> {
    warn_made_again(path, what, why);
    return std::nullopt;
  };
  KeptHeader h{};
  if (bytes->size() < sizeof(h)) return refuse("too short");
  std::memcpy(&h, bytes->data(), sizeof(h));
  if (std::string_view(h.magic, sizeof(h.magic)) != magic) return refuse("another magic");
  const std::string_view rest = std::string_view(*bytes).substr(sizeof(h));
  if (bulk_checksum(rest.data(), rest.size()) != h.checksum) return refuse("its checksum does not match");
  if (h.json_bytes > rest.size()) return refuse("its counts disagree with its size");
  try {
    return std::pair(nlohmann::json::parse(rest.substr(0, h.json_bytes)), std::string(rest.substr(h.json_bytes)));
  } catch (const std::exception& e) {
    return refuse(e.what());
  }
}

std::filesystem::path export_cache_folder(const std::filesystem::path& work) { return work / "export-cache"; }

KeptFolder::KeptFolder(std::filesystem::path dir, Kind kind) : dir_(std::move(dir)), kind_(kind) {}

std::filesystem::path KeptFolder::file(std::uint64_t digest) const {
  const std::uint64_t mixed[2] = {executable_identity(), digest};
  return dir_ / fmt::format("{:016x}{}", bulk_checksum(mixed, sizeof(mixed)), kind_.suffix);
}

std::optional<std::pair<nlohmann::json, std::string>> KeptFolder::find(std::uint64_t digest) const {
  const std::filesystem::path path = file(digest);
  auto kept = read_kept_file(path, kind_.magic, kind_.what);
  if (!kept) return std::nullopt;
  std::error_code ec;
  std::filesystem::last_write_time(path, std::filesystem::file_time_type::clock::now(), ec);  // used: kept
  return kept;
}

void KeptFolder::keep(std::uint64_t digest, std::string_view json, std::string_view bytes) const {
  write_kept_file(file(digest), kind_.magic, json, bytes);
}

void KeptFolder::prune(std::filesystem::file_time_type since) const {
  // Another node of a cluster may stamp by a clock a little behind this one's.
  const std::filesystem::file_time_type before = since - std::chrono::minutes(10);
  std::error_code ec;
  std::vector<std::filesystem::path> stale;
  for (const auto& entry : std::filesystem::directory_iterator(dir_, ec)) {
    if (!entry.path().string().ends_with(kind_.suffix)) continue;
    std::error_code time_ec;
    const auto time = std::filesystem::last_write_time(entry.path(), time_ec);
    if (!time_ec && time < before) stale.push_back(entry.path());
  }
  for (const std::filesystem::path& f : stale) std::filesystem::remove(f, ec);
}

ExportPrimitiveCache::ExportPrimitiveCache(const std::filesystem::path& dir)
    : files_(dir, {".glbp", "CMGLBP01", "an encoded tile"}) {}

std::optional<GlbPrimitive> ExportPrimitiveCache::find(std::uint64_t digest) const {
  return files_.find_as<GlbPrimitive>(digest, [](const nlohmann::json& json, const std::string& bytes) {
    return GlbPrimitive{json.at("primitive"), json.at("accessors"),
                        std::vector<std::uint8_t>(bytes.begin(), bytes.end())};
  });
}

void ExportPrimitiveCache::keep(std::uint64_t digest, const GlbPrimitive& primitive) {
  const nlohmann::json json{{"primitive", primitive.primitive}, {"accessors", primitive.accessors}};
  files_.keep(digest, json.dump(), {reinterpret_cast<const char*>(primitive.draco.data()), primitive.draco.size()});
}

ExportSimplifyCache::ExportSimplifyCache(const std::filesystem::path& dir)
    : files_(dir, {".simp", "CMSIMP01", "a simplified tile"}) {}

std::optional<SimplifiedMesh> ExportSimplifyCache::find(std::uint64_t digest) const {
  return files_.find_as<SimplifiedMesh>(digest, [](const nlohmann::json& json, const std::string& bytes) {
    SimplifiedMesh mesh;
    mesh.error = json.at("error").get<double>();
    const auto triangles = json.at("triangles").get<std::uint64_t>();
    if (bytes.size() != triangles * sizeof(Triangle)) throw std::runtime_error("its triangles are cut short");
    mesh.triangles.resize(triangles);
    std::memcpy(mesh.triangles.data(), bytes.data(), bytes.size());
    return mesh;
  });
}

void ExportSimplifyCache::keep(std::uint64_t digest, const SimplifiedMesh& mesh) {
  const nlohmann::json json{{"triangles", mesh.triangles.size()}, {"error", mesh.error}};
  files_.keep(digest, json.dump(),
              {reinterpret_cast<const char*>(mesh.triangles.data()), mesh.triangles.size() * sizeof(Triangle)});
}

}  // namespace citymesh::app
