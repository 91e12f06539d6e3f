// SPDX-License-Identifier: MIT
// The checksums of citymesh's binary files: enough to tell a torn or damaged file from a
// finished one. Bulk files (the tile store's blocks, tile results: gigabytes on a city) use
// XXH3, which runs at memory speed; small files (record files, config fingerprints) keep
// FNV-1a, so their formats did not change when XXH3 came in.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <type_traits>

struct XXH3_state_s;

namespace citymesh {

/// FNV-1a, 64 bit, one byte at a time (about 1 GB/s): for small files and texts.
inline std::uint64_t fnv1a(const void* data, std::size_t size, std::uint64_t hash = 0xcbf29ce484222325ull) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (std::size_t i = 0; i < size; ++i) hash = (hash ^ p[i]) * 0x100000001b3ull;
  return hash;
}

/// XXH3 (64 bit) of `data`: tens of GB/s, so checksumming costs nothing next to writing.
std::uint64_t bulk_checksum(const void* data, std::size_t size);

/// A digest of this program's executable file, its bytes (0 when it cannot be read): work
/// kept for later runs (tile results, stitched parts, encoded tiles) mixes it in, so that a
/// rebuilt or upgraded citymesh, whose code may give other results, never takes an older
/// build's. The same build copied or installed on every node of a cluster has one identity.
std::uint64_t executable_identity();

/// bulk_checksum of bytes given in parts: the parts' concatenation gives the same value.
class BulkChecksum {
 public:
  BulkChecksum();
  ~BulkChecksum();
  BulkChecksum(const BulkChecksum&) = delete;
  BulkChecksum& operator=(const BulkChecksum&) = delete;

  void add(const void* data, std::size_t size);
  /// The bytes of one value, of a type without padding (padding bytes are not the value's and
  /// would make equal values digest differently: give such a struct field by field).
  template <class T>
  void add_value(const T& value) {
    static_assert(std::is_trivially_copyable_v<T>);
    add(&value, sizeof(value));
  }
  /// An array's length, then its bytes: moving an element from one array to the next of a
  /// digest changes it.
  template <class T>
  void add_array(std::span<const T> values) {
    add_value(std::uint64_t{values.size()});
    add(values.data(), values.size_bytes());
  }
  [[nodiscard]] std::uint64_t value() const;

 private:
  XXH3_state_s* state_;
};

}  // namespace citymesh
