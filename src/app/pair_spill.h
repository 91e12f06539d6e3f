// SPDX-License-Identifier: MIT
// The consistent pairs of a tiled run, on disk until they are written: a city has ~90 M of
// them (0.7 GB), more than the final pass can hold next to the output mesh.
#pragma once

#include <cstdint>
#include <filesystem>
#include <span>
#include <string_view>
#include <vector>

#include "citymesh/change/detect.h"

namespace citymesh::app {

/// What the name of a final pass's spill folder starts with, before the process tag.
inline constexpr std::string_view kPairSpillPrefix = "pairs.";

/// This process's spill folder in the work folder `work`: <work>/pairs.<host>.<pid>.
std::filesystem::path pair_spill_folder(const std::filesystem::path& work);

/// Pairs appended in any order to files by range of their first triangle; written out sorted
/// and unique, one range at a time, so that memory holds one range's pairs at most.
class PairSpill {
 public:
  /// Pairs whose first triangle lies in [r * range, (r + 1) * range) share a file. A range
  /// of 2^20 triangles holds ~3 M pairs with their repeats from halos (~50 MB, sorted in
  /// twice that): 2^22 made this sort the final pass's peak on the 28 M-triangle city.
  static constexpr std::uint32_t kDefaultRange = 1u << 20;

  /// Creates `dir` (emptied first); it is removed with the spill.
  explicit PairSpill(std::filesystem::path dir, std::uint32_t range = kDefaultRange);
  ~PairSpill();
  PairSpill(const PairSpill&) = delete;
  PairSpill& operator=(const PairSpill&) = delete;

  /// Appends pairs (any order, repeats allowed; taken by value: grouped in place). Throws
  /// OutputError naming the file.
  void add(std::vector<TrianglePair> pairs);

  /// Writes every pair added, sorted and without repeats, as `magic` records (a0 b0 a1 b1
  /// ...) to `path` atomically; returns how many pairs. Throws InputError when a spill file
  /// was damaged, OutputError when `path` cannot be written.
  std::uint64_t write_sorted(const std::filesystem::path& path, std::string_view magic) const;

 private:
  [[nodiscard]] std::filesystem::path file(std::uint32_t range_index) const;

  std::filesystem::path dir_;
  std::uint32_t range_;
  std::uint32_t ranges_ = 0;  ///< 1 + the largest range index written
};

/// Every input triangle's labels, packed as the assembly keeps them, on disk until each
/// acquisition's labelled PLY is written: one file per acquisition in a folder that exists
/// (the pairs' spill folder), so that memory holds one acquisition's labels at a time.
class LabelSpill {
 public:
  struct Label {
    std::uint32_t index = 0;            ///< the triangle, in its acquisition
    std::uint8_t flags = 0;             ///< state and bits, as TileAssembly packs them
    std::uint16_t first = 0, last = 0;  ///< first and last seen, as indices of the dates met
  };

  explicit LabelSpill(std::filesystem::path dir) : dir_(std::move(dir)) {}

  /// Appends labels of `acquisition`. Throws OutputError naming the file.
  void add(std::uint32_t acquisition, std::span<const Label> labels);
  /// Acquisition `acquisition`'s labels by triangle index. Throws ProcessingError naming the
  /// acquisition unless each of its `count` triangles was labelled exactly once.
  [[nodiscard]] std::vector<Label> read(std::uint32_t acquisition, std::uint64_t count) const {
    return read(acquisition, count, 0, count);
  }
  /// The labels of its triangles [begin, end) by triangle index (element 0: triangle begin),
  /// read through the file in bounded steps. Throws ProcessingError naming the acquisition
  /// unless the file holds `count` labels, and each triangle of the range exactly once.
  [[nodiscard]] std::vector<Label> read(std::uint32_t acquisition, std::uint64_t count, std::uint64_t begin,
                                        std::uint64_t end) const;

  /// Appends triangles of `acquisition` that another tile than their owner found refuting
  /// (any order, repeats allowed). Throws OutputError naming the file.
  void add_refuted(std::uint32_t acquisition, std::span<const std::uint32_t> indices);
  /// Those in [begin, end), sorted, each once. Throws ProcessingError naming the acquisition
  /// when one is not among its `count` triangles.
  [[nodiscard]] std::vector<std::uint32_t> refuted(std::uint32_t acquisition, std::uint64_t count, std::uint64_t begin,
                                                   std::uint64_t end) const;

 private:
  [[nodiscard]] std::filesystem::path file(std::uint32_t acquisition, std::string_view kind = "labels") const;
  std::filesystem::path dir_;
};

}  // namespace citymesh::app
