// SPDX-License-Identifier: MIT
#include "citymesh/core/checksum.h"

#include <xxhash.h>

#include <filesystem>
#include <new>
#include <system_error>

namespace citymesh {

std::uint64_t bulk_checksum(const void* data, std::size_t size) { return XXH3_64bits(data, size); }

std::uint64_t executable_identity() {
  static const std::uint64_t identity = [] {
    std::error_code ec;
    const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
    if (ec) return std::uint64_t{0};
    const std::uintmax_t size = std::filesystem::file_size(exe, ec);
    if (ec) return std::uint64_t{0};
    const auto time = std::filesystem::last_write_time(exe, ec).time_since_epoch().count();
    if (ec) return std::uint64_t{0};
    const std::uint64_t parts[2] = {static_cast<std::uint64_t>(size), static_cast<std::uint64_t>(time)};
    return bulk_checksum(parts, sizeof(parts));
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
