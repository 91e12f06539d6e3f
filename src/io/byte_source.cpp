// SPDX-License-Identifier: MIT
#include "byte_source.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>

#include "citymesh/core/error.h"

namespace citymesh {

ByteSource::ByteSource(const std::filesystem::path& path, std::uint64_t start, std::size_t capacity)
    : path_(path), buffer_(capacity), file_offset_(start) {
  fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  struct stat st {};
  if (fd_ < 0 || ::fstat(fd_, &st) != 0) {
    throw InputError(fmt::format("{}: cannot open: {}", path.string(), std::strerror(errno)));
  }
  file_size_ = static_cast<std::uint64_t>(st.st_size);
  if (::lseek(fd_, static_cast<off_t>(start), SEEK_SET) < 0) {
    throw InputError(fmt::format("{}: cannot seek: {}", path.string(), std::strerror(errno)));
  }
  ::posix_fadvise(fd_, 0, 0, POSIX_FADV_SEQUENTIAL);
}

ByteSource::~ByteSource() {
  if (fd_ >= 0) ::close(fd_);
}

bool ByteSource::refill(std::size_t n) {
  if (begin_ > 0) {  // move the unread tail to the front
    std::memmove(buffer_.data(), buffer_.data() + begin_, end_ - begin_);
    end_ -= begin_;
    begin_ = 0;
  }
  if (n > buffer_.size()) buffer_.resize(n);
  while (end_ < n) {
    const ssize_t got = ::read(fd_, buffer_.data() + end_, buffer_.size() - end_);
    if (got < 0) {
      if (errno == EINTR) continue;
      throw InputError(fmt::format("{}: read error: {}", path_.string(), std::strerror(errno)));
    }
    if (got == 0) return false;
    end_ += static_cast<std::size_t>(got);
    file_offset_ += static_cast<std::uint64_t>(got);
  }
  return true;
}

bool ByteSource::next_line(std::string_view& line, std::size_t max_line) {
  std::size_t scanned = 0;
  while (true) {
    const char* data = buffer_.data() + begin_;
    const std::size_t available = end_ - begin_;
    const void* nl = std::memchr(data + scanned, '\n', available - scanned);
    if (nl != nullptr) {
      const auto length = static_cast<std::size_t>(static_cast<const char*>(nl) - data);
      line = std::string_view(data, length);
      if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
      begin_ += length + 1;
      return true;
    }
    scanned = available;
    if (available > max_line) {
      throw InputError(fmt::format("{}: a line is longer than {} bytes", path_.string(), max_line));
    }
    if (!refill(available + 1)) {  // last line without a newline
      if (end_ == begin_) return false;
      line = std::string_view(buffer_.data() + begin_, end_ - begin_);
      if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
      begin_ = end_;
      return true;
    }
  }
}

}  // namespace citymesh
