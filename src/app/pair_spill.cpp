// SPDX-License-Identifier: MIT
#include "pair_spill.h"

#include <fmt/format.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <memory>
#include <vector>

#include "citymesh/core/atomic_file.h"
#include "citymesh/core/error.h"
#include "citymesh/core/radix_sort.h"
#include "citymesh/core/record_file.h"

namespace citymesh::app {

std::filesystem::path pair_spill_folder(const std::filesystem::path& work) {
  return work / (std::string(kPairSpillPrefix) + process_tag());
}

PairSpill::PairSpill(std::filesystem::path dir, std::uint32_t range)
    : dir_(std::move(dir)), range_(std::max(range, 1u)) {
  std::error_code ec;
  std::filesystem::remove_all(dir_, ec);
  std::filesystem::create_directories(dir_, ec);
  if (ec) throw OutputError(fmt::format("{}: cannot create a folder for the pairs: {}", dir_.string(), ec.message()));
}

PairSpill::~PairSpill() {
  std::error_code ec;
  std::filesystem::remove_all(dir_, ec);  // best effort: a leftover holds no finished output
}

std::filesystem::path PairSpill::file(std::uint32_t range_index) const {
  return dir_ / fmt::format("{}.pairs", range_index);
}

void PairSpill::add(std::vector<TrianglePair> pairs) {
  // Grouped by range, then one append per file. A tile's pairs come sorted by their first
  // triangle, hence grouped already: checked in one pass, sorted (stably) only if not.
  const auto by_range = [&](const TrianglePair& x, const TrianglePair& y) {
    return x.first / range_ < y.first / range_;
  };
  if (!std::is_sorted(pairs.begin(), pairs.end(), by_range)) std::stable_sort(pairs.begin(), pairs.end(), by_range);
  for (auto begin = pairs.begin(); begin != pairs.end();) {
    const std::uint32_t r = begin->first / range_;
    const auto end = std::find_if(begin, pairs.end(), [&](const TrianglePair& p) { return p.first / range_ != r; });
    const std::filesystem::path spilled = file(r);
    std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(std::fopen(spilled.c_str(), "ab"), &std::fclose);
    const auto count = static_cast<std::size_t>(end - begin);
    if (!f || std::fwrite(&*begin, sizeof(TrianglePair), count, f.get()) != count || std::fflush(f.get()) != 0) {
      throw OutputError(fmt::format("{}: cannot append pairs: {}", spilled.string(), std::strerror(errno)));
    }
    ranges_ = std::max(ranges_, r + 1);
    begin = end;
  }
}

std::uint64_t PairSpill::write_sorted(const std::filesystem::path& path, std::string_view magic) const {
  static_assert(sizeof(TrianglePair) == 2 * sizeof(std::uint32_t));
  U32RecordWriter out(path, magic);
  std::vector<TrianglePair> pairs;
  for (std::uint32_t r = 0; r < ranges_; ++r) {
    const std::filesystem::path spilled = file(r);
    std::error_code ec;
    const std::uintmax_t size = std::filesystem::file_size(spilled, ec);
    if (ec) continue;  // no pair starts in this range
    std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(std::fopen(spilled.c_str(), "rb"), &std::fclose);
    pairs.resize(size / sizeof(TrianglePair));
    if (size % sizeof(TrianglePair) != 0 || !f ||
        std::fread(pairs.data(), sizeof(TrianglePair), pairs.size(), f.get()) != pairs.size()) {
      throw InputError(fmt::format("{}: cannot read the spilled pairs back whole", spilled.string()));
    }
    radix_sort_pairs(pairs);
    pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
    out.add(std::span(reinterpret_cast<const std::uint32_t*>(pairs.data()), 2 * pairs.size()));
  }
  const std::uint64_t count = out.count() / 2;
  out.commit();
  return count;
}

namespace {

/// A label on disk: index (4 bytes), flags (1), first and last (2 each), little-endian.
constexpr std::size_t kLabelBytes = 9;
/// Labels read from the file at a time.
constexpr std::size_t kLabelsPerRead = 1 << 16;

}  // namespace

std::filesystem::path LabelSpill::file(std::uint32_t acquisition, std::string_view kind) const {
  return dir_ / fmt::format("{}.{}", acquisition, kind);
}

namespace {

void append_bytes(const std::filesystem::path& spilled, const void* data, std::size_t size, std::string_view what) {
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(std::fopen(spilled.c_str(), "ab"), &std::fclose);
  if (!f || std::fwrite(data, 1, size, f.get()) != size || std::fflush(f.get()) != 0) {
    throw OutputError(fmt::format("{}: cannot append {}: {}", spilled.string(), what, std::strerror(errno)));
  }
}

}  // namespace

void LabelSpill::add(std::uint32_t acquisition, std::span<const Label> labels) {
  std::vector<unsigned char> bytes(labels.size() * kLabelBytes);
  for (std::size_t i = 0; i < labels.size(); ++i) {
    unsigned char* at = bytes.data() + i * kLabelBytes;
    std::memcpy(at, &labels[i].index, 4);
    at[4] = labels[i].flags;
    std::memcpy(at + 5, &labels[i].first, 2);
    std::memcpy(at + 7, &labels[i].last, 2);
  }
  append_bytes(file(acquisition), bytes.data(), bytes.size(), "labels");
}

void LabelSpill::add_refuted(std::uint32_t acquisition, std::span<const std::uint32_t> indices) {
  append_bytes(file(acquisition, "refuted"), indices.data(), indices.size_bytes(), "refuted triangles");
}

std::vector<std::uint32_t> LabelSpill::refuted(std::uint32_t acquisition, std::uint64_t count, std::uint64_t begin,
                                               std::uint64_t end) const {
  const std::filesystem::path spilled = file(acquisition, "refuted");
  std::error_code ec;
  if (!std::filesystem::exists(spilled, ec)) return {};
  const std::uintmax_t size = std::filesystem::file_size(spilled, ec);
  if (ec || size % 4 != 0) throw InputError(fmt::format("{}: damaged (not whole triangle indices)", spilled.string()));
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(std::fopen(spilled.c_str(), "rb"), &std::fclose);
  if (!f)
    throw InputError(
        fmt::format("{}: cannot read the spilled triangles back: {}", spilled.string(), std::strerror(errno)));
  std::vector<std::uint32_t> out, chunk(kLabelsPerRead);
  for (std::uintmax_t left = size / 4; left > 0;) {
    const auto n = static_cast<std::size_t>(std::min<std::uintmax_t>(kLabelsPerRead, left));
    if (std::fread(chunk.data(), 4, n, f.get()) != n) {
      throw InputError(fmt::format("{}: cannot read the spilled triangles back whole", spilled.string()));
    }
    for (std::size_t i = 0; i < n; ++i) {
      if (chunk[i] >= count) {
        throw ProcessingError(
            fmt::format("tile assembly: triangle {} of acquisition {} refuting but not in it (its "
                        "file has {})",
                        chunk[i], acquisition, count));
      }
      if (chunk[i] >= begin && chunk[i] < end) out.push_back(chunk[i]);
    }
    left -= n;
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

std::vector<LabelSpill::Label> LabelSpill::read(std::uint32_t acquisition, std::uint64_t count, std::uint64_t begin,
                                                std::uint64_t end) const {
  const std::filesystem::path spilled = file(acquisition);
  std::error_code ec;
  const std::uintmax_t size = std::filesystem::exists(spilled, ec) ? std::filesystem::file_size(spilled, ec) : 0;
  if (ec || size != count * kLabelBytes || begin > end || end > count) {
    throw ProcessingError(
        fmt::format("tile assembly: {} labels of acquisition {} from the tiles, its file has {} "
                    "triangles (a tile is missing or labelled twice)",
                    size / kLabelBytes, acquisition, count));
  }
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(std::fopen(spilled.c_str(), "rb"), &std::fclose);
  if (!f)
    throw InputError(
        fmt::format("{}: cannot read the spilled labels back: {}", spilled.string(), std::strerror(errno)));
  std::vector<Label> out(static_cast<std::size_t>(end - begin));
  std::vector<std::uint8_t> seen(out.size(), 0);
  std::vector<unsigned char> bytes(kLabelsPerRead * kLabelBytes);
  for (std::uint64_t done = 0; done < count;) {
    const auto n = static_cast<std::size_t>(std::min<std::uint64_t>(kLabelsPerRead, count - done));
    if (std::fread(bytes.data(), kLabelBytes, n, f.get()) != n) {
      throw InputError(fmt::format("{}: cannot read the spilled labels back whole", spilled.string()));
    }
    for (std::size_t i = 0; i < n; ++i) {
      const unsigned char* at = bytes.data() + i * kLabelBytes;
      Label l;
      std::memcpy(&l.index, at, 4);
      if (l.index >= count) {
        throw ProcessingError(
            fmt::format("tile assembly: triangle {} of acquisition {} labelled but not in it (its "
                        "file has {})",
                        l.index, acquisition, count));
      }
      if (l.index < begin || l.index >= end) continue;
      l.flags = at[4];
      std::memcpy(&l.first, at + 5, 2);
      std::memcpy(&l.last, at + 7, 2);
      if (seen[l.index - begin] != 0) {
        throw ProcessingError(
            fmt::format("tile assembly: triangle {} of acquisition {} labelled twice (its file has {})", l.index,
                        acquisition, count));
      }
      seen[l.index - begin] = 1;
      out[l.index - begin] = l;
    }
    done += n;
  }
  const auto missing = std::find(seen.begin(), seen.end(), std::uint8_t{0});
  if (missing != seen.end()) {
    throw ProcessingError(fmt::format("tile assembly: triangle {} of acquisition {} not labelled (a tile is missing)",
                                      begin + static_cast<std::uint64_t>(missing - seen.begin()), acquisition));
  }
  return out;
}

}  // namespace citymesh::app
