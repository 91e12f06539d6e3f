// SPDX-License-Identifier: MIT
// Crash-safe file output: write to a temporary name, fsync, then rename over the final name,
// so that no half-written file is ever taken for finished work.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>
#include <string_view>

namespace citymesh {

/// What AtomicFile puts between the final name and the process tag of its temporary file.
inline constexpr std::string_view kTemporaryInfix = ".tmp.";

class AtomicFile {
 public:
  /// Opens "<final>.tmp.<host>.<pid>" for writing (unique across the machines of a cluster
  /// sharing the folder). Throws OutputError naming the file.
  explicit AtomicFile(std::filesystem::path final_path);
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;
  /// Removes the temporary file unless commit() succeeded.
  ~AtomicFile();

  void write(const void* data, std::size_t size);
  void write(std::string_view text) { write(text.data(), text.size()); }
  /// Overwrites bytes already written at `offset` (a header whose values are known last),
  /// then goes on writing at the end.
  void write_at(std::uint64_t offset, const void* data, std::size_t size);
  /// Flushes, fsyncs, renames onto the final path and fsyncs the folder.
  void commit();

  [[nodiscard]] const std::filesystem::path& path() const { return final_path_; }

 private:
  std::filesystem::path final_path_;
  std::filesystem::path temp_path_;
  std::FILE* file_ = nullptr;
  bool committed_ = false;
};

/// "<host>.<pid>": names this process's temporary files and folders uniquely among the
/// processes of every machine sharing a folder.
std::string process_tag();

/// Whether `tag` ("<host>.<pid>", as process_tag() makes it) names a process of this machine
/// that is no longer running: what such a process left behind (a temporary file, a folder of
/// its own) is nobody's. False for another machine's tag (its processes cannot be checked from
/// here), for a live process and for anything that is not a tag.
bool tag_of_ended_local_process(std::string_view tag);

/// Writes `content` to `path` atomically.
void write_file_atomically(const std::filesystem::path& path, std::string_view content);

/// fsyncs a folder, so that names renamed into it survive a crash (best effort: some
/// filesystems refuse folder handles).
void sync_directory(const std::filesystem::path& dir);

/// Where a folder replaced with replace_directory_atomically is built: "<target>.partial".
std::filesystem::path staging_directory(const std::filesystem::path& target);

/// Puts the finished folder `staged` in place of `target` in one step (the old `target`, if
/// any, is swapped out and removed), then fsyncs their parent: readers see the old folder or
/// the complete new one, never a mix. Throws OutputError naming the folders.
void replace_directory_atomically(const std::filesystem::path& staged, const std::filesystem::path& target);

}  // namespace citymesh
