// SPDX-License-Identifier: MIT
// PLY structure: formats, scalar types, elements and the parsed header.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "citymesh/core/vec.h"

namespace citymesh {

enum class PlyFormat { ascii, binary_little_endian, binary_big_endian };
enum class PlyScalar : std::uint8_t { int8, uint8, int16, uint16, int32, uint32, float32, float64 };

[[nodiscard]] std::size_t ply_scalar_size(PlyScalar type);
/// Canonical name as written by citymesh ("uchar", "int", "double", ...).
[[nodiscard]] std::string_view ply_scalar_name(PlyScalar type);
/// Accepts both spellings ("uchar"/"uint8", "float"/"float32", ...).
[[nodiscard]] std::optional<PlyScalar> parse_ply_scalar(std::string_view name);
[[nodiscard]] std::string_view ply_format_name(PlyFormat format);

struct PlyProperty {
  std::string name;
  PlyScalar type = PlyScalar::float32;  ///< the value type (of list items for lists)
  bool is_list = false;
  PlyScalar count_type = PlyScalar::uint8;  ///< lists only
};

struct PlyElement {
  std::string name;
  std::uint64_t count = 0;
  std::vector<PlyProperty> properties;

  /// Bytes per row in a binary file when no property is a list.
  [[nodiscard]] std::optional<std::size_t> fixed_row_size() const;
  /// Smallest possible row in the file's format (empty lists; "0 " per ascii value).
  [[nodiscard]] std::size_t min_row_size(PlyFormat format) const;
  [[nodiscard]] const PlyProperty* find(std::string_view property) const;
};

struct PlyHeader {
  PlyFormat format = PlyFormat::binary_little_endian;
  std::vector<std::string> comments;
  std::vector<PlyElement> elements;
  /// Offset from an IGN header comment ("comment offset Pos E N H" or "comment IGN offset Pos
  /// E N H"), added to positions and sensor positions so they come out absolute.
  Vec3d offset;
  std::size_t header_bytes = 0;  ///< bytes up to and including the end_header line

  [[nodiscard]] const PlyElement* find(std::string_view element) const;
};

/// Parses and validates a header: structure, types, and that the declared element counts can
/// fit in the bytes that follow it (`file_size`), so that no absurd count is ever allocated.
/// `text` holds at least the whole header; `path` only names the file in errors.
/// Throws InputError ("<file>: header line 4: ...").
PlyHeader parse_ply_header(std::string_view text, std::uint64_t file_size,
                           const std::filesystem::path& path);

}  // namespace citymesh
