// SPDX-License-Identifier: MIT
// Temporary name + fsync + rename: readers see either the old file or the complete new one.
#include "citymesh/core/atomic_file.h"

#include <fcntl.h>
#include <signal.h>
#include <fmt/format.h>
#include <unistd.h>

#include <stdio.h>  // renameat2

#include <cerrno>
#include <cstring>
#include <system_error>

#include "citymesh/core/error.h"

namespace citymesh {

namespace {
[[noreturn]] void fail(const std::filesystem::path& path, std::string_view action) {
  throw OutputError(fmt::format("{}: cannot {}: {}", path.string(), action, std::strerror(errno)));
}

}  // namespace

void sync_directory(const std::filesystem::path& dir) {
  const int fd = ::open(dir.empty() ? "." : dir.c_str(), O_RDONLY | O_DIRECTORY);
  if (fd < 0) return;
  ::fsync(fd);
  ::close(fd);
}

/// This machine's name, empty when it cannot be had.
std::string host_name() {
  char host[256] = {};
  if (::gethostname(host, sizeof host - 1) != 0) host[0] = '\0';
  return host;
}

std::string process_tag() { return fmt::format("{}.{}", host_name(), ::getpid()); }

bool tag_of_ended_local_process(std::string_view tag) {
  const std::size_t dot = tag.rfind('.');
  if (dot == std::string_view::npos || dot + 1 == tag.size() || tag.size() - dot > 10) return false;
  long pid = 0;
  for (const char c : tag.substr(dot + 1)) {
    if (c < '0' || c > '9') return false;
    pid = pid * 10 + (c - '0');
  }
  if (pid <= 0 || pid == ::getpid()) return false;
  const std::string host = host_name();
  if (host.empty() || tag.substr(0, dot) != host) return false;
  // ESRCH: no such process. EPERM means it runs under another user: alive.
  return ::kill(static_cast<pid_t>(pid), 0) != 0 && errno == ESRCH;
}

AtomicFile::AtomicFile(std::filesystem::path final_path) : final_path_(std::move(final_path)) {
  temp_path_ = final_path_;
  temp_path_ += std::string(kTemporaryInfix) + process_tag();
  std::error_code ec;
  if (final_path_.has_parent_path()) std::filesystem::create_directories(final_path_.parent_path(), ec);
  file_ = std::fopen(temp_path_.c_str(), "wb");
  if (file_ == nullptr) fail(temp_path_, "open for writing");
}

AtomicFile::~AtomicFile() {
  if (file_ != nullptr) std::fclose(file_);
  if (!committed_) {
    std::error_code ec;
    std::filesystem::remove(temp_path_, ec);
  }
}

void AtomicFile::write(const void* data, std::size_t size) {
  if (size != 0 && std::fwrite(data, 1, size, file_) != size) fail(temp_path_, "write");
}

void AtomicFile::write_at(std::uint64_t offset, const void* data, std::size_t size) {
  if (std::fseek(file_, static_cast<long>(offset), SEEK_SET) != 0) fail(temp_path_, "seek");
  write(data, size);
  if (std::fseek(file_, 0, SEEK_END) != 0) fail(temp_path_, "seek");
}

void AtomicFile::commit() {
  if (std::fflush(file_) != 0) fail(temp_path_, "flush");
  if (::fsync(::fileno(file_)) != 0) fail(temp_path_, "fsync");
  const int closed = std::fclose(file_);
  file_ = nullptr;
  if (closed != 0) fail(temp_path_, "close");
  if (std::rename(temp_path_.c_str(), final_path_.c_str()) != 0) fail(final_path_, "rename into place");
  committed_ = true;
  sync_directory(final_path_.parent_path());
}

void write_file_atomically(const std::filesystem::path& path, std::string_view content) {
  AtomicFile file(path);
  file.write(content);
  file.commit();
}

std::filesystem::path staging_directory(const std::filesystem::path& target) {
  std::filesystem::path staged = target;
  staged += ".partial";
  return staged;
}

void replace_directory_atomically(const std::filesystem::path& staged, const std::filesystem::path& target) {
  sync_directory(staged);
  std::error_code ec;
  if (!std::filesystem::exists(target, ec)) {
    if (std::rename(staged.c_str(), target.c_str()) != 0) fail(target, "rename the staged folder onto");
  } else {
    if (::renameat2(AT_FDCWD, staged.c_str(), AT_FDCWD, target.c_str(), RENAME_EXCHANGE) != 0) {
      fail(target, "swap in the staged folder");
    }
    std::filesystem::remove_all(staged, ec);  // now the old content
  }
  sync_directory(target.parent_path());
}

}  // namespace citymesh
