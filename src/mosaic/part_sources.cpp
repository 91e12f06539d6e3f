// SPDX-License-Identifier: MIT
#include "part_sources.h"

#include <algorithm>
#include <cstdint>

#include "citymesh/mosaic/merged_mesh.h"

namespace citymesh::mosaic_detail {

namespace {

/// The sources seen so far, ascending: a handful (the passes over one part), met millions of
/// times (every vertex and triangle), mostly the one met last.
class SourceSet {
 public:
  void add(std::uint32_t s) {
    if (s == last_) return;
    last_ = s;
    const auto it = std::lower_bound(sorted_.begin(), sorted_.end(), s);
    if (it == sorted_.end() || *it != s) sorted_.insert(it, s);
  }
  std::vector<std::uint32_t> take() { return std::move(sorted_); }

 private:
  std::vector<std::uint32_t> sorted_;
  std::uint32_t last_ = UINT32_MAX;
};

/// Adds the sources `piece` holds to `set`.
void add_sources(const KeyedPiece& piece, SourceSet& set) {
  for (const std::uint64_t key : piece.keys) {
    if (key >= kNewVertexKey) break;  // keys ascend: the new vertices come last
    set.add(input_vertex_source(key));
  }
  for (std::size_t t = 0; t < piece.triangle_count(); ++t) {
    if (piece.source_acq[t] == kNoSource) continue;  // a stitch triangle: no source, an empty id
    set.add(static_cast<std::uint32_t>(piece.source_acq[t]));
    set.add(piece.ids[t].acquisition);
  }
}

/// `piece` with each source s named rename(s), or nothing when rename has no name for one.
/// `rename` keeps the order of the sources, so the keys still ascend.
template <class Rename>
std::optional<KeyedPiece> renamed(const KeyedPiece& piece, const Rename& rename) {
  KeyedPiece out = piece;
  for (std::uint64_t& key : out.keys) {
    if (key >= kNewVertexKey) break;
    const std::optional<std::uint32_t> s = rename(input_vertex_source(key));
    if (!s) return std::nullopt;
    key = input_vertex_key(*s, static_cast<std::uint32_t>(key));
  }
  for (std::size_t t = 0; t < out.triangle_count(); ++t) {
    if (out.source_acq[t] == kNoSource) continue;
    const std::optional<std::uint32_t> s = rename(static_cast<std::uint32_t>(out.source_acq[t]));
    const std::optional<std::uint32_t> id = rename(out.ids[t].acquisition);
    if (!s || !id) return std::nullopt;
    out.source_acq[t] = static_cast<std::int32_t>(*s);
    out.ids[t].acquisition = *id;
  }
  return out;
}

}  // namespace

SourceRanks::SourceRanks(const KeyedPiece& own, std::span<const Neighbour> around) {
  SourceSet set;
  add_sources(own, set);
  for (const Neighbour& n : around) add_sources(*n.piece, set);
  sources_ = set.take();
  identity_ = sources_.empty() || sources_.back() + 1 == sources_.size();
}

std::optional<KeyedPiece> SourceRanks::to_ranks(const KeyedPiece& piece) const {
  return renamed(piece, [&](std::uint32_t s) -> std::optional<std::uint32_t> {
    const auto it = std::lower_bound(sources_.begin(), sources_.end(), s);
    if (it == sources_.end() || *it != s) return std::nullopt;
    return static_cast<std::uint32_t>(it - sources_.begin());
  });
}

std::optional<KeyedPiece> SourceRanks::from_ranks(const KeyedPiece& piece) const {
  return renamed(piece, [&](std::uint32_t r) -> std::optional<std::uint32_t> {
    if (r >= sources_.size()) return std::nullopt;
    return sources_[r];
  });
}

}  // namespace citymesh::mosaic_detail
