// SPDX-License-Identifier: MIT
// Whole binary files into memory in one read (tile chunks, tile results, glb files): reading
// through stream iterators went byte by byte and cost seconds per gigabyte.
#pragma once

#include <filesystem>
#include <optional>
#include <string>

namespace citymesh {

/// The bytes of `file`, or nullopt when it cannot be opened (missing, a folder, no
/// permission). A read that fails part-way throws InputError naming the file.
std::optional<std::string> read_file_bytes(const std::filesystem::path& file);

}  // namespace citymesh
