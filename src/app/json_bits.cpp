// SPDX-License-Identifier: MIT
#include "json_bits.h"

#include <bit>
#include <cstdint>

namespace citymesh::app {

nlohmann::json double_bits(double v) { return std::bit_cast<std::uint64_t>(v); }

double double_from_bits(const nlohmann::json& j) { return std::bit_cast<double>(j.get<std::uint64_t>()); }

nlohmann::json box_bits(const Box3d& b) {
  nlohmann::json out = nlohmann::json::array();
  for (const double v : {b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z}) out.push_back(double_bits(v));
  return out;
}

Box3d box_from_bits(const nlohmann::json& j) {
  const auto at = [&](std::size_t k) { return double_from_bits(j.at(k)); };
  Box3d b;
  b.min = {at(0), at(1), at(2)};
  b.max = {at(3), at(4), at(5)};
  return b;
}

nlohmann::json float_bits(float v) { return std::bit_cast<std::uint32_t>(v); }
float float_from_bits(const nlohmann::json& j) { return std::bit_cast<float>(j.get<std::uint32_t>()); }

nlohmann::json tile_key_json(const TileKey& k) { return {k.i, k.j}; }

nlohmann::json block_part_key_json(const BlockPartKey& k) { return {k.level, k.x, k.y}; }

BlockPartKey block_part_key_from(const nlohmann::json& j) {
  if (!j.is_array() || j.size() != 3) throw ProcessingError("a seam part's key is not [level, x, y]");
  return {j.at(0).get<int>(), j.at(1).get<std::int64_t>(), j.at(2).get<std::int64_t>()};
}

nlohmann::json block_part_keys_json(std::span<const BlockPartKey> keys) {
  nlohmann::json rows = nlohmann::json::array();
  for (const BlockPartKey& k : keys) rows.push_back(block_part_key_json(k));
  return rows;
}

std::vector<BlockPartKey> block_part_keys_from(const nlohmann::json& rows) {
  std::vector<BlockPartKey> keys;
  for (const auto& r : rows) keys.push_back(block_part_key_from(r));
  return keys;
}

TileKey tile_key_from(const nlohmann::json& j) { return {j.at(0).get<std::int32_t>(), j.at(1).get<std::int32_t>()}; }

}  // namespace citymesh::app
