// SPDX-License-Identifier: MIT
// Arrays of plain values as raw bytes, for the scratch files ranks and passes hand each other
// (seam parts, 3D Tiles cells): written whole, read back with their counts checked first.
#pragma once

#include <cstring>
#include <string>
#include <string_view>
#include <vector>

namespace citymesh::app {

/// Appends the bytes of `values`.
template <class T>
void put_array(std::string& out, const std::vector<T>& values) {
  if (values.empty()) return;  // an empty vector's data() may be null
  out.append(reinterpret_cast<const char*>(values.data()), values.size() * sizeof(T));
}

/// Reads `count` values from the front of `in` (which the caller checked holds them).
template <class T>
void take_array(std::string_view& in, std::vector<T>& values, std::size_t count) {
  values.resize(count);
  if (count == 0) return;  // no bytes, and data() may be null
  std::memcpy(values.data(), in.data(), count * sizeof(T));
  in.remove_prefix(count * sizeof(T));
}

}  // namespace citymesh::app
