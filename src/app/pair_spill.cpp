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

PairSpill::PairSpill(std::filesystem::path dir, std::uint32_t range) : dir_(std::move(dir)), range_(std::max(range, 1u)) {
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
  const auto by_range = [&](const TrianglePair& x, const TrianglePair& y) { return x.first / range_ < y.first / range_; };
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
    if (size % sizeof(TrianglePair) != 0 || !f || std::fread(pairs.data(), sizeof(TrianglePair), pairs.size(), f.get()) != pairs.size()) {
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

}  // namespace citymesh::app
