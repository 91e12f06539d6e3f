// SPDX-License-Identifier: MIT
// Writes arbitrary PLY files (any format, any property types) for reader tests. Deliberately
// independent of the project's writer, so that reader and writer are checked against each other.
#pragma once

#include <bit>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "citymesh/io/ply.h"

namespace citymesh::test {

struct PropSpec {
  std::string name;
  PlyScalar type = PlyScalar::float32;
  bool is_list = false;
  PlyScalar count_type = PlyScalar::uint8;
};

struct ElementSpec {
  std::string name;
  std::vector<PropSpec> props;
  /// rows[r][p] holds the values of property p in row r (one value for a scalar).
  std::vector<std::vector<std::vector<double>>> rows;
};

inline void put_binary(std::string& out, double v, PlyScalar t, bool big_endian) {
  char bytes[8];
  std::size_t n = ply_scalar_size(t);
  switch (t) {
    case PlyScalar::int8: { auto x = static_cast<std::int8_t>(v); std::memcpy(bytes, &x, n); break; }
    case PlyScalar::uint8: { auto x = static_cast<std::uint8_t>(v); std::memcpy(bytes, &x, n); break; }
    case PlyScalar::int16: { auto x = static_cast<std::int16_t>(v); std::memcpy(bytes, &x, n); break; }
    case PlyScalar::uint16: { auto x = static_cast<std::uint16_t>(v); std::memcpy(bytes, &x, n); break; }
    case PlyScalar::int32: { auto x = static_cast<std::int32_t>(v); std::memcpy(bytes, &x, n); break; }
    case PlyScalar::uint32: { auto x = static_cast<std::uint32_t>(v); std::memcpy(bytes, &x, n); break; }
    case PlyScalar::float32: { auto x = static_cast<float>(v); std::memcpy(bytes, &x, n); break; }
    case PlyScalar::float64: { std::memcpy(bytes, &v, n); break; }
  }
  if (big_endian) {
    for (std::size_t i = 0; i < n / 2; ++i) std::swap(bytes[i], bytes[n - 1 - i]);
  }
  out.append(bytes, n);
}

inline std::string ascii_value(double v, PlyScalar t) {
  if (t == PlyScalar::float32) return fmt::format("{}", static_cast<float>(v));
  if (t == PlyScalar::float64) return fmt::format("{}", v);
  return fmt::format("{}", static_cast<std::int64_t>(v));
}

inline std::string build_ply(PlyFormat format, const std::vector<ElementSpec>& elements,
                             const std::vector<std::string>& comments = {}) {
  std::string out = fmt::format("ply\nformat {} 1.0\n", ply_format_name(format));
  for (const auto& c : comments) out += "comment " + c + "\n";
  for (const auto& e : elements) {
    out += fmt::format("element {} {}\n", e.name, e.rows.size());
    for (const auto& p : e.props) {
      out += p.is_list ? fmt::format("property list {} {} {}\n", ply_scalar_name(p.count_type), ply_scalar_name(p.type), p.name)
                       : fmt::format("property {} {}\n", ply_scalar_name(p.type), p.name);
    }
  }
  out += "end_header\n";
  const bool big = format == PlyFormat::binary_big_endian;
  for (const auto& e : elements) {
    for (const auto& row : e.rows) {
      std::string line;
      for (std::size_t p = 0; p < e.props.size(); ++p) {
        const auto& spec = e.props[p];
        if (format == PlyFormat::ascii) {
          if (spec.is_list) line += fmt::format("{} ", row[p].size());
          for (double v : row[p]) line += ascii_value(v, spec.type) + " ";
        } else {
          if (spec.is_list) put_binary(out, static_cast<double>(row[p].size()), spec.count_type, big);
          for (double v : row[p]) put_binary(out, v, spec.type, big);
        }
      }
      if (format == PlyFormat::ascii) {
        line.pop_back();
        out += line + "\n";
      }
    }
  }
  return out;
}

}  // namespace citymesh::test
