// SPDX-License-Identifier: MIT
#include "citymesh/core/record_file.h"

#include <fmt/format.h>

#include <cstring>
#include <fstream>

#include "citymesh/core/atomic_file.h"
#include "citymesh/core/checksum.h"
#include "citymesh/core/error.h"

namespace citymesh {

namespace {

constexpr std::size_t kMagicSize = 8;
constexpr std::size_t kFrame = kMagicSize + 2 * sizeof(std::uint64_t);  // magic, count, checksum

}  // namespace

void write_u32_records(const std::filesystem::path& path, std::string_view magic, std::span<const std::uint32_t> values) {
  U32RecordWriter file(path, magic);
  file.add(values);
  file.commit();
}

U32RecordWriter::U32RecordWriter(const std::filesystem::path& path, std::string_view magic)
    : file_(std::make_unique<AtomicFile>(path)), sum_(fnv1a(nullptr, 0)) {
  file_->write(magic.data(), kMagicSize);
  file_->write(&count_, sizeof count_);  // filled in by commit()
}

U32RecordWriter::~U32RecordWriter() = default;

void U32RecordWriter::add(std::span<const std::uint32_t> values) {
  file_->write(values.data(), values.size_bytes());
  sum_ = fnv1a(values.data(), values.size_bytes(), sum_);
  count_ += values.size();
}

void U32RecordWriter::commit() {
  file_->write(&sum_, sizeof sum_);
  file_->write_at(kMagicSize, &count_, sizeof count_);
  file_->commit();
}

std::vector<std::uint32_t> read_u32_records(const std::filesystem::path& path, std::string_view magic,
                                            std::string_view what) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(fmt::format("{}: cannot open {}", path.string(), what));
  char head[kMagicSize];
  std::uint64_t count = 0, sum = 0;
  if (!in.read(head, kMagicSize) || std::memcmp(head, magic.data(), kMagicSize) != 0) {
    throw InputError(fmt::format("{}: not a citymesh {} file", path.string(), what));
  }
  in.read(reinterpret_cast<char*>(&count), sizeof count);
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  // The count is checked against the file size before anything is allocated.
  if (!in || ec || size < kFrame || (size - kFrame) % 4 != 0 || count != (size - kFrame) / 4) {
    throw InputError(fmt::format("{}: {} is truncated or its count is wrong", path.string(), what));
  }
  std::vector<std::uint32_t> values(count);
  in.read(reinterpret_cast<char*>(values.data()), static_cast<std::streamsize>(count * 4));
  in.read(reinterpret_cast<char*>(&sum), sizeof sum);
  if (!in || sum != fnv1a(values.data(), values.size() * 4)) {
    throw InputError(fmt::format("{}: {} checksum mismatch", path.string(), what));
  }
  return values;
}

}  // namespace citymesh
