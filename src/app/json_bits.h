// SPDX-License-Identifier: MIT
// The JSON files MPI ranks hand each other: doubles and boxes as their bits (a box or a frame
// must come back exactly, an empty box is infinite, and a sum over ranks must equal one
// process's), grid keys, and reading such a file with a clear error when it is missing or
// not what was expected.
#pragma once

#include <fmt/format.h>

#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "citymesh/core/error.h"
#include "citymesh/core/read_file.h"
#include "citymesh/core/vec.h"
#include "citymesh/mosaic/stitch_blocks.h"
#include "citymesh/tiler/tile_grid.h"

namespace citymesh::app {

nlohmann::json double_bits(double v);
double double_from_bits(const nlohmann::json& j);
nlohmann::json float_bits(float v);
float float_from_bits(const nlohmann::json& j);

nlohmann::json box_bits(const Box3d& b);
Box3d box_from_bits(const nlohmann::json& j);

nlohmann::json tile_key_json(const TileKey& k);
TileKey tile_key_from(const nlohmann::json& j);
/// A seam part's key as [level, x, y], and back (ProcessingError when it is not three numbers).
nlohmann::json block_part_key_json(const BlockPartKey& k);
BlockPartKey block_part_key_from(const nlohmann::json& j);
/// A list of them.
nlohmann::json block_part_keys_json(std::span<const BlockPartKey> keys);
std::vector<BlockPartKey> block_part_keys_from(const nlohmann::json& rows);

/// `decode(the JSON in file)`; throws ProcessingError naming the file when it is missing
/// ("missing (`what`)") or holds something `decode` does not expect ("malformed").
template <class Decode>
auto decode_json_file(const std::filesystem::path& file, std::string_view what, Decode decode) {
  const std::optional<std::string> text = read_file_bytes(file);
  if (!text) throw ProcessingError(fmt::format("{}: missing ({})", file.string(), what));
  try {
    return decode(nlohmann::json::parse(*text));
  } catch (const nlohmann::json::exception& e) {
    throw ProcessingError(fmt::format("{}: malformed ({})", file.string(), e.what()));
  }
}

/// decode_json_file(), then the file is removed: what another rank left for this one.
template <class Decode>
auto take_json_file(const std::filesystem::path& file, std::string_view what, Decode decode) {
  auto result = decode_json_file(file, what, decode);
  std::filesystem::remove(file);
  return result;
}

}  // namespace citymesh::app
