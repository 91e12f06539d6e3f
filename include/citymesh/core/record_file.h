// SPDX-License-Identifier: MIT
// Small binary side files: an 8-byte magic, a count, that many uint32 values and an FNV-1a
// checksum, written atomically (ground truth per face, the change step's pair list).
#pragma once

#include <cstdint>
#include <filesystem>
#include <span>
#include <string_view>
#include <vector>

namespace citymesh {

/// `magic` must be exactly 8 characters. Throws OutputError naming the file.
void write_u32_records(const std::filesystem::path& path, std::string_view magic, std::span<const std::uint32_t> values);

/// Throws InputError naming the file and `what` when it is missing, has another magic, is
/// truncated or its checksum does not match.
std::vector<std::uint32_t> read_u32_records(const std::filesystem::path& path, std::string_view magic,
                                            std::string_view what);

}  // namespace citymesh
