// SPDX-License-Identifier: MIT
// Decoding one PLY scalar from binary (either byte order) or ascii text.
#pragma once

#include <charconv>
#include <cstdint>
#include <cstring>
#include <optional>
#include <string_view>
#include <utility>

#include "citymesh/io/ply.h"

namespace citymesh::ply_detail {

/// Reads a T stored at p, reversing its bytes when the file's byte order differs from ours
/// (compilers turn the loop into a single bswap).
template <class T>
inline T load_raw(const char* p, bool swap) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, p, sizeof(T));
  if (swap) {
    for (std::size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(bytes[i], bytes[sizeof(T) - 1 - i]);
  }
  T value;
  std::memcpy(&value, bytes, sizeof(T));
  return value;
}

inline double load_double(const char* p, PlyScalar type, bool swap) {
  switch (type) {
    case PlyScalar::int8: return load_raw<std::int8_t>(p, swap);
    case PlyScalar::uint8: return load_raw<std::uint8_t>(p, swap);
    case PlyScalar::int16: return load_raw<std::int16_t>(p, swap);
    case PlyScalar::uint16: return load_raw<std::uint16_t>(p, swap);
    case PlyScalar::int32: return load_raw<std::int32_t>(p, swap);
    case PlyScalar::uint32: return load_raw<std::uint32_t>(p, swap);
    case PlyScalar::float32: return static_cast<double>(load_raw<float>(p, swap));
    case PlyScalar::float64: return load_raw<double>(p, swap);
  }
  return 0;
}

/// Integer types only (list counts and indices).
inline std::int64_t load_int(const char* p, PlyScalar type, bool swap) {
  switch (type) {
    case PlyScalar::int8: return load_raw<std::int8_t>(p, swap);
    case PlyScalar::uint8: return load_raw<std::uint8_t>(p, swap);
    case PlyScalar::int16: return load_raw<std::int16_t>(p, swap);
    case PlyScalar::uint16: return load_raw<std::uint16_t>(p, swap);
    case PlyScalar::int32: return load_raw<std::int32_t>(p, swap);
    case PlyScalar::uint32: return load_raw<std::uint32_t>(p, swap);
    default: return 0;
  }
}

/// Splits an ascii row into values.
class AsciiTokens {
 public:
  explicit AsciiTokens(std::string_view line) : rest_(line) {}
  bool next(std::string_view& token) {
    std::size_t i = 0;
    while (i < rest_.size() && (rest_[i] == ' ' || rest_[i] == '\t')) ++i;
    std::size_t start = i;
    while (i < rest_.size() && rest_[i] != ' ' && rest_[i] != '\t') ++i;
    token = rest_.substr(start, i - start);
    rest_.remove_prefix(i);
    return !token.empty();
  }

 private:
  std::string_view rest_;
};

inline std::optional<double> parse_double(std::string_view s) {
  double v = 0;
  auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (ec != std::errc() || end != s.data() + s.size()) return std::nullopt;
  return v;
}

inline std::optional<std::int64_t> parse_int(std::string_view s) {
  std::int64_t v = 0;
  auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (ec != std::errc() || end != s.data() + s.size()) return std::nullopt;
  return v;
}

}  // namespace citymesh::ply_detail
