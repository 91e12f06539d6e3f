// SPDX-License-Identifier: MIT
// Buffered sequential file reading with contiguous look-ahead, for the PLY reader.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <string_view>
#include <vector>

namespace citymesh {

class ByteSource {
 public:
  /// Opens `path` positioned at byte `start`. Throws InputError naming the file.
  ByteSource(const std::filesystem::path& path, std::uint64_t start, std::size_t capacity = 4u << 20);
  ~ByteSource();
  ByteSource(const ByteSource&) = delete;
  ByteSource& operator=(const ByteSource&) = delete;

  /// At least `n` contiguous bytes at the read position, or nullptr when the file ends first.
  const char* peek(std::size_t n) {
    if (end_ - begin_ >= n) return buffer_.data() + begin_;
    return refill(n) ? buffer_.data() + begin_ : nullptr;
  }
  void skip(std::size_t n) { begin_ += n; }
  /// Next line without its "\n" or "\r\n"; false at the end of the file. A line longer than
  /// `max_line` throws InputError.
  bool next_line(std::string_view& line, std::size_t max_line = 1u << 20);
  /// Bytes left between the read position and the end of the file.
  [[nodiscard]] std::uint64_t remaining() const { return file_size_ - (file_offset_ - (end_ - begin_)); }

 private:
  bool refill(std::size_t n);

  const std::filesystem::path& path_;
  int fd_ = -1;
  std::vector<char> buffer_;
  std::size_t begin_ = 0, end_ = 0;
  std::uint64_t file_offset_ = 0;  // file offset of buffer_[end_]
  std::uint64_t file_size_ = 0;
};

}  // namespace citymesh
