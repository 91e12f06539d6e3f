// SPDX-License-Identifier: MIT
// Binary files, or ranges of them, into memory in one read (tile blocks, tile results, glb
// files): reading through stream iterators went byte by byte and cost seconds per gigabyte.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <span>
#include <string>

namespace citymesh {

/// The bytes of `file`, or nullopt when it cannot be opened (missing, a folder, no
/// permission). A read that fails part-way throws InputError naming the file.
std::optional<std::string> read_file_bytes(const std::filesystem::path& file);

/// `bytes` bytes of a file from byte `offset` on.
struct ByteRange {
  std::uint64_t offset = 0, bytes = 0;
  friend bool operator==(const ByteRange&, const ByteRange&) = default;
};

/// The bytes of `ranges` of `file`, one after another. Every range is checked against the
/// file's size before memory is taken for it, so a damaged index cannot ask for more than the
/// file holds. Throws InputError starting with `source` (the file and what is read from it)
/// when the file cannot be opened or read or a range passes its end.
std::string read_file_ranges(const std::filesystem::path& file, std::span<const ByteRange> ranges,
                             std::string_view source);

}  // namespace citymesh
