// SPDX-License-Identifier: MIT
// Work kept in the work folder for later runs (stitched parts, encoded tiles, simplified
// parents): one file per item, found by a digest of its inputs. A file is written under a temporary name and renamed
// (no fsync: a torn one fails its checksum and the item is made again, like a missing one).
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <utility>

#include "citymesh/encode/glb.h"
#include "citymesh/tiles3d/simplify.h"

namespace citymesh::app {

/// Writes `path`: `magic` (8 bytes), the sizes, an XXH3 of the rest, `json`, `bytes`. Best
/// effort: a failure is a warning (the item is made again next time).
void write_kept_file(const std::filesystem::path& path, std::string_view magic, std::string_view json,
                     std::string_view bytes);

/// The JSON and bytes of a file write_kept_file() wrote whole; nullopt when there is none, and
/// (with a warning naming it and `what`) when it is damaged.
std::optional<std::pair<nlohmann::json, std::string>> read_kept_file(const std::filesystem::path& path,
                                                                     std::string_view magic, std::string_view what);

/// Warns that `path`, `what` an earlier run kept, cannot be used (`why`): it is made again.
void warn_made_again(const std::filesystem::path& path, std::string_view what, std::string_view why);

/// <work>/export-cache: where the export's caches keep encoded tiles and simplified parents.
std::filesystem::path export_cache_folder(const std::filesystem::path& work);

/// Kept files of one kind in one folder, one per item: "<digest>.<suffix>", the digest mixed
/// with the build's identity (another build may make an item otherwise). An item found has
/// its file's time set to now, so that prune() keeps what this run used, whichever process of
/// the run used it.
class KeptFolder {
 public:
  struct Kind {
    std::string_view suffix;  ///< with its dot
    std::string_view magic;   ///< 8 bytes
    std::string_view what;    ///< for warnings: "an encoded tile"
  };
  KeptFolder(std::filesystem::path dir, Kind kind);
  /// The JSON and bytes kept for `digest`; nullopt when none is (or it is damaged).
  [[nodiscard]] std::optional<std::pair<nlohmann::json, std::string>> find(std::uint64_t digest) const;
  /// The item kept for `digest` as `decode(json, bytes)` makes it; nullopt when none is, or
  /// when decode throws (the file is then made again, with a warning).
  template <class T, class Decode>
  [[nodiscard]] std::optional<T> find_as(std::uint64_t digest, Decode decode) const {
    auto kept = find(digest);
    if (!kept) return std::nullopt;
    try {
      return decode(kept->first, kept->second);
    } catch (const std::exception& e) {
      warn_made_again(file(digest), kind_.what, e.what());
      return std::nullopt;
    }
  }
  void keep(std::uint64_t digest, std::string_view json, std::string_view bytes) const;
  /// Removes the items neither kept nor found since `since` (less a margin for the clocks of
  /// a cluster's nodes). Best effort.
  void prune(std::filesystem::file_time_type since) const;

 private:
  [[nodiscard]] std::filesystem::path file(std::uint64_t digest) const;
  std::filesystem::path dir_;
  Kind kind_;
};

/// The export's encoded tiles: "<digest>.glbp" (magic `CMGLBP01`).
class ExportPrimitiveCache final : public GlbPrimitiveCache {
 public:
  explicit ExportPrimitiveCache(const std::filesystem::path& dir);
  [[nodiscard]] std::optional<GlbPrimitive> find(std::uint64_t digest) const override;
  void keep(std::uint64_t digest, const GlbPrimitive& primitive) override;
  void prune(std::filesystem::file_time_type since) const { files_.prune(since); }

 private:
  KeptFolder files_;
};

/// The export's parents as simplified: "<digest>.simp" (magic `CMSIMP01`), the triangles kept
/// and the error.
class ExportSimplifyCache final : public SimplifyCache {
 public:
  explicit ExportSimplifyCache(const std::filesystem::path& dir);
  [[nodiscard]] std::optional<SimplifiedMesh> find(std::uint64_t digest) const override;
  void keep(std::uint64_t digest, const SimplifiedMesh& mesh) override;
  void prune(std::filesystem::file_time_type since) const { files_.prune(since); }

 private:
  KeptFolder files_;
};

/// Both of the export's caches in one work folder.
struct ExportCaches {
  explicit ExportCaches(const std::filesystem::path& work)
      : primitives(export_cache_folder(work)), simplified(export_cache_folder(work)) {}
  ExportPrimitiveCache primitives;
  ExportSimplifyCache simplified;
  void prune(std::filesystem::file_time_type since) const {
    primitives.prune(since);
    simplified.prune(since);
  }
};

}  // namespace citymesh::app
