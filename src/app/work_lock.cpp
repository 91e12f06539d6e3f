// SPDX-License-Identifier: MIT
#include "work_lock.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <fstream>
#include <sstream>

#include "citymesh/core/atomic_file.h"
#include "citymesh/core/error.h"
#include "citymesh/core/log.h"
#include "citymesh/core/time.h"

namespace citymesh::app {

namespace {

constexpr const char* kLockFile = "run.lock";

/// What the holder wrote into the lock file ("" when nothing): its process and start time.
std::string holder(const std::filesystem::path& file) {
  std::ifstream in(file);
  std::stringstream text;
  text << in.rdbuf();
  std::string s = text.str();
  while (!s.empty() && (s.back() == '\n' || s.back() == '\r')) s.pop_back();
  return s.empty() ? std::string() : fmt::format(" ({})", s);
}

}  // namespace

WorkFolderLock::WorkFolderLock(const std::filesystem::path& work, bool exclusive) {
  std::error_code ec;
  std::filesystem::create_directories(work, ec);
  const std::filesystem::path file = work / kLockFile;
  fd_ = ::open(file.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd_ < 0) {
    throw OutputError(fmt::format("{}: cannot make the work folder's lock: {}", file.string(), std::strerror(errno)));
  }
  if (::flock(fd_, (exclusive ? LOCK_EX : LOCK_SH) | LOCK_NB) != 0) {
    const int error = errno;
    ::close(fd_);
    fd_ = -1;
    if (error != EWOULDBLOCK) {
      // A file system without locks (some network mounts) must not stop the run.
      log::warn("{}: cannot lock the work folder ({}): make sure no other citymesh run uses it", file.string(),
                std::strerror(error));
      return;
    }
    throw OutputError(fmt::format(
        "{}: the work folder is in use by another citymesh run{}; wait for it to end, or give this run another "
        "[project] work folder",
        work.string(), holder(file)));
  }
  if (!exclusive) return;  // subsets share it: none of them names itself
  const std::string who = fmt::format(
      "{}, since {}\n", process_tag(),
      format_iso8601(std::chrono::time_point_cast<std::chrono::milliseconds>(std::chrono::system_clock::now())));
  if (::ftruncate(fd_, 0) == 0) {
    [[maybe_unused]] const ssize_t written = ::pwrite(fd_, who.data(), who.size(), 0);
  }
}

WorkFolderLock::~WorkFolderLock() {
  if (fd_ >= 0) ::close(fd_);  // releases the lock
}

}  // namespace citymesh::app
