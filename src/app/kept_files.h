// SPDX-License-Identifier: MIT
// Work kept in the work folder for later runs (stitched parts, encoded tiles): one file per
// item, found by a digest of its inputs. A file is written under a temporary name and renamed
// (no fsync: a torn one fails its checksum and the item is made again, like a missing one).
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <utility>

#include "citymesh/encode/glb.h"

namespace citymesh::app {

/// Writes `path`: `magic` (8 bytes), the sizes, an XXH3 of the rest, `json`, `bytes`. Best
/// effort: a failure is a warning (the item is made again next time).
void write_kept_file(const std::filesystem::path& path, std::string_view magic, std::string_view json,
                     std::string_view bytes);

/// The JSON and bytes of a file write_kept_file() wrote whole; nullopt when there is none, and
/// (with a warning naming it and `what`) when it is damaged.
std::optional<std::pair<nlohmann::json, std::string>> read_kept_file(const std::filesystem::path& path,
                                                                     std::string_view magic, std::string_view what);

/// <work>/export-cache: where ExportPrimitiveCache keeps the encoded tiles.
std::filesystem::path export_cache_folder(const std::filesystem::path& work);

/// A GlbPrimitiveCache in one folder, one file per primitive: "<digest>.glbp" (magic
/// `CMGLBP01`). The digest mixes in the build. A primitive found has its file's time set to
/// now, so that prune() keeps what this run used, whichever process of the run used it.
class ExportPrimitiveCache final : public GlbPrimitiveCache {
 public:
  explicit ExportPrimitiveCache(std::filesystem::path dir);
  [[nodiscard]] std::optional<GlbPrimitive> find(std::uint64_t digest) const override;
  void keep(std::uint64_t digest, const GlbPrimitive& primitive) override;
  /// Removes the primitives neither kept nor found since `since` (less a margin for the
  /// clocks of a cluster's nodes). Best effort.
  void prune(std::filesystem::file_time_type since) const;

 private:
  [[nodiscard]] std::filesystem::path file(std::uint64_t digest) const;
  std::filesystem::path dir_;
};

}  // namespace citymesh::app
