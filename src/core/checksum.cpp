// SPDX-License-Identifier: MIT
#include "citymesh/core/checksum.h"

#include <xxhash.h>

#include <new>

namespace citymesh {

std::uint64_t bulk_checksum(const void* data, std::size_t size) { return XXH3_64bits(data, size); }

BulkChecksum::BulkChecksum() : state_(XXH3_createState()) {
  if (state_ == nullptr) throw std::bad_alloc();
  XXH3_64bits_reset(state_);
}

BulkChecksum::~BulkChecksum() { XXH3_freeState(state_); }

void BulkChecksum::add(const void* data, std::size_t size) { XXH3_64bits_update(state_, data, size); }

std::uint64_t BulkChecksum::value() const { return XXH3_64bits_digest(state_); }

}  // namespace citymesh
