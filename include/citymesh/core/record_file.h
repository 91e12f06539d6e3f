// SPDX-License-Identifier: MIT
// Small binary side files: an 8-byte magic, a count, that many uint32 values and an FNV-1a
// checksum, written atomically (ground truth per face, the change step's pair list).
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>
#include <string_view>
#include <vector>

namespace citymesh {

class AtomicFile;

/// `magic` must be exactly 8 characters. Throws OutputError naming the file.
void write_u32_records(const std::filesystem::path& path, std::string_view magic, std::span<const std::uint32_t> values);

/// The same file written in parts (a list too large to hold at once): the count is filled
/// in by commit(). Nothing appears under `path` unless commit() is reached.
class U32RecordWriter {
 public:
  U32RecordWriter(const std::filesystem::path& path, std::string_view magic);
  ~U32RecordWriter();
  U32RecordWriter(const U32RecordWriter&) = delete;
  U32RecordWriter& operator=(const U32RecordWriter&) = delete;
  void add(std::span<const std::uint32_t> values);
  [[nodiscard]] std::uint64_t count() const { return count_; }
  void commit();

 private:
  std::unique_ptr<AtomicFile> file_;
  std::uint64_t count_ = 0, sum_;
};

/// Throws InputError naming the file and `what` when it is missing, has another magic, is
/// truncated or its checksum does not match.
std::vector<std::uint32_t> read_u32_records(const std::filesystem::path& path, std::string_view magic,
                                            std::string_view what);

}  // namespace citymesh
