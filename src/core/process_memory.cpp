// SPDX-License-Identifier: MIT
#include "citymesh/core/process_memory.h"

#include <fstream>
#include <string>

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

}  // namespace citymesh
