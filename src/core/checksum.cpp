// SPDX-License-Identifier: MIT
#include "citymesh/core/checksum.h"

#include <xxhash.h>

#include <fstream>
#include <new>
#include <vector>

namespace citymesh {

std::uint64_t bulk_checksum(const void* data, std::size_t size) { return XXH3_64bits(data, size); }

std::uint64_t executable_identity() {
  // The executable's bytes, not its size and time: the same build installed on every node of
  // a cluster (or copied, or reinstalled) is the same build.
  static const std::uint64_t identity = [] {
    std::ifstream in("/proc/self/exe", std::ios::binary);
    if (!in) return std::uint64_t{0};
    BulkChecksum sum;
    std::vector<char> buffer(std::size_t{1} << 20);
    while (in) {
      in.read(buffer.data(), static_cast<std::streamsize>(buffer.size()));
      sum.add(buffer.data(), static_cast<std::size_t>(in.gcount()));
    }
    return in.eof() ? sum.value() : std::uint64_t{0};
  }();
  return identity;
}

BulkChecksum::BulkChecksum() : state_(XXH3_createState()) {
  if (state_ == nullptr) throw std::bad_alloc();
  XXH3_64bits_reset(state_);
}

BulkChecksum::~BulkChecksum() { XXH3_freeState(state_); }

void BulkChecksum::add(const void* data, std::size_t size) { XXH3_64bits_update(state_, data, size); }

std::uint64_t BulkChecksum::value() const { return XXH3_64bits_digest(state_); }

}  // namespace citymesh
