// SPDX-License-Identifier: MIT
#include "citymesh/core/read_file.h"

#include <fmt/format.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <memory>

#include "citymesh/core/error.h"

namespace citymesh {

namespace {

struct CloseFile {
  void operator()(std::FILE* f) const { std::fclose(f); }
};

}  // namespace

std::optional<std::string> read_file_bytes(const std::filesystem::path& file) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(file, ec)) return std::nullopt;
  const std::unique_ptr<std::FILE, CloseFile> f(std::fopen(file.c_str(), "rb"));
  if (!f) return std::nullopt;
  std::string bytes;
  // The size is a hint (the file may change under us): read until the end either way.
  const std::uintmax_t size = std::filesystem::file_size(file, ec);
  if (!ec) bytes.resize(static_cast<std::size_t>(size));
  bytes.resize(std::fread(bytes.data(), 1, bytes.size(), f.get()));
  char chunk[65536];
  while (std::feof(f.get()) == 0 && std::ferror(f.get()) == 0) {
    const std::size_t n = std::fread(chunk, 1, sizeof chunk, f.get());
    bytes.append(chunk, n);
  }
  if (std::ferror(f.get()) != 0) {
    throw InputError(fmt::format("{}: cannot read: {}", file.string(), std::strerror(errno)));
  }
  return bytes;
}

std::string read_file_ranges(const std::filesystem::path& file, std::span<const ByteRange> ranges,
                             std::string_view source) {
  const std::unique_ptr<std::FILE, CloseFile> f(std::fopen(file.c_str(), "rb"));
  if (!f) throw InputError(fmt::format("{}: cannot open: {}", source, std::strerror(errno)));
  std::error_code ec;
  const std::uintmax_t size = std::filesystem::file_size(file, ec);
  if (ec) throw InputError(fmt::format("{}: cannot tell the size: {}", source, ec.message()));
  std::uint64_t total = 0;
  for (const ByteRange& r : ranges) {
    if (r.offset > size || r.bytes > size - r.offset) {
      throw InputError(fmt::format("{}: {} bytes at byte {} pass the file's end ({} bytes)", source, r.bytes, r.offset,
                                   size));
    }
    total += r.bytes;
  }
  std::string bytes(static_cast<std::size_t>(total), '\0');
  std::size_t at = 0;
  for (const ByteRange& r : ranges) {
    const bool ok = fseeko(f.get(), static_cast<off_t>(r.offset), SEEK_SET) == 0 &&
                    std::fread(bytes.data() + at, 1, r.bytes, f.get()) == r.bytes;
    if (!ok) throw InputError(fmt::format("{}: cannot read {} bytes at byte {}", source, r.bytes, r.offset));
    at += r.bytes;
  }
  return bytes;
}

}  // namespace citymesh
