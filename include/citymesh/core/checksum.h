// SPDX-License-Identifier: MIT
// The checksum of every citymesh binary file (FNV-1a, 64 bit): cheap, and enough to tell a
// torn or damaged file from a finished one.
#pragma once

#include <cstddef>
#include <cstdint>

namespace citymesh {

inline std::uint64_t fnv1a(const void* data, std::size_t size, std::uint64_t hash = 0xcbf29ce484222325ull) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (std::size_t i = 0; i < size; ++i) hash = (hash ^ p[i]) * 0x100000001b3ull;
  return hash;
}

}  // namespace citymesh
