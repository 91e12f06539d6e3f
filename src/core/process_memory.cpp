// SPDX-License-Identifier: MIT
#include "citymesh/core/process_memory.h"

#include <fmt/format.h>

#include <fstream>
#include <limits>
#include <string>

#if defined(__GLIBC__)
#include <malloc.h>
#include <unistd.h>
#endif

namespace citymesh {

namespace {
/// A "Name:   1234 kB" line of /proc/self/status, in bytes.
std::uint64_t status_kib(const std::string& name) {
  std::ifstream in("/proc/self/status");
  std::string key;
  std::uint64_t kib = 0;
  while (in >> key) {
    if (key == name + ":") {
      in >> kib;
      return kib * 1024;
    }
    std::getline(in, key);
  }
  return 0;
}
}  // namespace

std::uint64_t resident_bytes() { return status_kib("VmRSS"); }
std::uint64_t peak_resident_bytes() { return status_kib("VmHWM"); }

std::uint64_t physical_memory_bytes() {
  const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGESIZE);
  return pages > 0 && page > 0 ? static_cast<std::uint64_t>(pages) * static_cast<std::uint64_t>(page) : 0;
}

std::uint64_t memory_left(std::uint64_t budget) {
  const std::uint64_t resident = resident_bytes();
  return budget > resident ? budget - resident : 0;
}

std::string memory_note() {
  return fmt::format("resident {} MiB (peak {} MiB)", resident_bytes() >> 20, peak_resident_bytes() >> 20);
}

void keep_freed_memory_for_reuse() {
#if defined(__GLIBC__)
  constexpr int kNever = std::numeric_limits<int>::max();
  // Both or neither: a heap that may not mmap but still trims gives pages back all the same.
  mallopt(M_MMAP_THRESHOLD, kNever);
  mallopt(M_TRIM_THRESHOLD, kNever);
#endif
}

void release_freed_memory() {
#if defined(__GLIBC__)
  malloc_trim(0);
#endif
}

}  // namespace citymesh
