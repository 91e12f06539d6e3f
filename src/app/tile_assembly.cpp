// SPDX-License-Identifier: MIT
#include "tile_assembly.h"

#include <fmt/format.h>

#include <algorithm>
#include <utility>

#include "citymesh/core/error.h"
#include "citymesh/core/radix_sort.h"
#include "citymesh/mosaic/mosaic.h"

namespace citymesh::app {

namespace {

constexpr std::uint8_t kKeptBit = 1u << 2, kSustainableBit = 1u << 3, kRefutesBit = 1u << 4, kStateMask = 3u;

/// Throws ProcessingError naming the tile unless triangle t of acquisition a is in the store.
void check_in(const TileStore& store, const TileResult& result, std::uint32_t a, std::uint32_t t) {
  if (a >= store.triangles.size() || t >= store.triangles[a]) {
    throw ProcessingError(
        fmt::format("tile {}: triangle {} of acquisition {} is not in the tile store", result.key.name(), t, a));
  }
}

}  // namespace

TileAssembly::TileAssembly(const TileStore& store, std::optional<std::filesystem::path> pairs_dir) : store_(store) {
  index_.offsets.assign(1, 0);
  for (const std::uint64_t n : store.triangles) index_.offsets.push_back(index_.offsets.back() + n);
  if (index_.size() > UINT32_MAX) {
    throw ProcessingError(fmt::format("{} triangles in all: global ids are 32-bit", index_.size()));
  }
  if (!pairs_dir) return;
  pairs_.emplace(*pairs_dir);
  labels_.emplace(*pairs_dir);
}

std::uint16_t TileAssembly::date_index(std::int64_t ms) {
  // A handful of dates (the acquisitions'): a scan beats a map.
  const auto it = std::find(dates_ms_.begin(), dates_ms_.end(), ms);
  if (it != dates_ms_.end()) return static_cast<std::uint16_t>(it - dates_ms_.begin());
  if (dates_ms_.size() > UINT16_MAX) throw ProcessingError("tile assembly: more than 65536 distinct label dates");
  dates_ms_.push_back(ms);
  return static_cast<std::uint16_t>(dates_ms_.size() - 1);
}

void TileAssembly::check_in_store(const TileResult& result, std::uint32_t a, std::uint32_t t) const {
  check_in(store_, result, a, t);
}

TileTally tally_of(const TileResult& result, const TileStore& store) {
  TileTally t;
  for (const OwnedLabel& l : result.labels) {
    check_in(store, result, l.acquisition, l.index);
    ++t.owned;
    t.candidates += l.kept;
    t.seen_through += (l.notes & kNoteSeenThrough) != 0 ? 1 : 0;
    t.filled += (l.notes & kNoteFilled) != 0 ? 1 : 0;
    t.fill_left_out += (l.notes & kNoteFillLeftOut) != 0 ? 1 : 0;
  }
  t.change = result.change;
  t.seconds_read = result.seconds_read;
  t.seconds_detect = result.seconds_detect;
  t.seconds_mosaic = result.seconds_mosaic;
  return t;
}

void TileAssembly::add_tally(const TileTally& tally) {
  if (labels_) throw ProcessingError("tile assembly: a tile's labels are needed, not only its tally");
  count(tally);
}

void TileAssembly::count(const TileTally& tally) {
  change_.add(tally.change);
  owned_ += tally.owned;
  candidates_ += tally.candidates;
  seen_through_ += tally.seen_through;
  filled_ += tally.filled;
  fill_left_out_ += tally.fill_left_out;
}

void TileAssembly::add(TileResult result) {
  count(tally_of(result, store_));  // checks every label against the store
  if (labels_) spill_labels(result);
  for (TilePiece& p : result.selected) {
    if (p.triangle_count() > 0) pieces_.push_back(std::move(p));
  }
}

void TileAssembly::spill_labels(const TileResult& result) {
  const auto global = [&](std::uint32_t a, std::uint32_t t) -> std::uint32_t {
    check_in_store(result, a, t);
    return static_cast<std::uint32_t>(index_.offsets[a] + t);
  };
  // The labels wait on disk, per acquisition (a city's are several times the final pass's
  // memory): the tile hands them over grouped by acquisition.
  std::vector<LabelSpill::Label> spilled;
  const auto spill = [&](std::uint32_t acquisition) {
    if (!spilled.empty()) labels_->add(acquisition, spilled);
    spilled.clear();
  };
  for (std::size_t i = 0; i < result.labels.size(); ++i) {
    const OwnedLabel& l = result.labels[i];
    if (i > 0 && result.labels[i - 1].acquisition != l.acquisition) spill(result.labels[i - 1].acquisition);
    spilled.push_back(
        {l.index,
         static_cast<std::uint8_t>(static_cast<std::uint8_t>(l.state) | (l.kept != 0 ? kKeptBit : 0) |
                                   (l.sustainable != 0 ? kSustainableBit : 0) | (l.refutes != 0 ? kRefutesBit : 0)),
         date_index(l.first_ms), date_index(l.last_ms)});
  }
  if (!result.labels.empty()) spill(result.labels.back().acquisition);
  spill_refuted(result);
  // Spilled a bounded run at a time: a spinning scanner's tile holds 56 M pairs, 0.45 GB
  // as global pairs.
  constexpr std::size_t kPairsAtOnce = std::size_t{1} << 20;
  std::vector<TrianglePair> pairs;
  for (const LabelPair& p : result.pairs) {
    pairs.emplace_back(global(p.a_acquisition, p.a_index), global(p.b_acquisition, p.b_index));
    if (pairs.size() == kPairsAtOnce) pairs_->add(std::exchange(pairs, {}));
  }
  if (!pairs.empty()) pairs_->add(std::move(pairs));
}

void TileAssembly::spill_refuted(const TileResult& result) {
  std::vector<std::uint32_t> indices;
  for (std::size_t i = 0; i < result.refuted.size(); ++i) {
    const RefutedCopy& c = result.refuted[i];
    check_in_store(result, c.acquisition, c.index);
    indices.push_back(c.index);
    if (i + 1 == result.refuted.size() || result.refuted[i + 1].acquisition != c.acquisition) {
      labels_->add_refuted(c.acquisition, indices);
      indices.clear();
    }
  }
}

MergedMesh TileAssembly::take_merged() {
  // Every selected triangle by its flat number (piece_start[p] + t), gathered per
  // acquisition as (triangle index, flat number): sorted, the output order is the input's.
  std::vector<std::uint32_t> piece_start{0};
  std::vector<std::vector<std::pair<std::uint32_t, std::uint32_t>>> by_acquisition(store_.triangles.size());
  std::vector<std::uint32_t> vertex_ids_end(store_.triangles.size(), 0);  ///< 1 + largest vertex id used
  bool intensities = true, colors = true;
  for (const TilePiece& piece : pieces_) {
    intensities = intensities && !piece.mesh.intensities.empty();
    colors = colors && !piece.mesh.colors.empty();
    for (std::uint32_t t = 0; t < piece.triangle_count(); ++t) {
      const std::uint32_t a = piece.mesh.triangle_ids[t].acquisition;
      by_acquisition[a].emplace_back(piece.triangle_index[t], piece_start.back() + t);
      for (const std::uint32_t v : piece.mesh.triangles[t]) {
        vertex_ids_end[a] = std::max(vertex_ids_end[a], piece.vertex_ids[v] + 1);
      }
    }
    piece_start.push_back(piece_start.back() + static_cast<std::uint32_t>(piece.triangle_count()));
  }
  MergedMesh out;
  Mesh& m = out.mesh;
  // Room at once (the triangles exactly, the vertices at most the pieces' own): growing by
  // doubling copied the arrays of a city's output several times over.
  std::size_t vertex_room = 0;
  for (const TilePiece& piece : pieces_) vertex_room += piece.vertex_ids.size();
  const std::size_t triangles = piece_start.back();
  m.positions.reserve(vertex_room);
  m.sensor_positions.reserve(vertex_room);
  if (intensities) m.intensities.reserve(vertex_room);
  if (colors) m.colors.reserve(vertex_room);
  m.triangles.reserve(triangles);
  m.triangle_ids.reserve(triangles);
  out.source_acq.reserve(triangles);
  out.source_triangle.reserve(triangles);
  bool origin_set = false;
  // Vertex id in the acquisition -> merged vertex: a dense table, one acquisition at a time
  // (a hash map of every vertex took most of the assembly).
  std::vector<std::uint32_t> merged_vertex;
  for (std::uint32_t a = 0; a < by_acquisition.size(); ++a) {
    auto& order = by_acquisition[a];
    radix_sort_pairs(order);
    merged_vertex.assign(vertex_ids_end[a], UINT32_MAX);
    for (const auto& [index, flat] : order) {
      const auto p = static_cast<std::size_t>(std::upper_bound(piece_start.begin(), piece_start.end(), flat) -
                                              piece_start.begin() - 1);
      const TilePiece& piece = pieces_[p];
      const std::uint32_t t = flat - piece_start[p];
      if (!origin_set) {
        m.origin = whole_metre_origin(piece.mesh.world_position(piece.mesh.triangles[t][0]));
        origin_set = true;
      }
      Triangle tri{};
      for (std::size_t c = 0; c < 3; ++c) {
        const std::uint32_t v = piece.mesh.triangles[t][c];
        std::uint32_t& slot = merged_vertex[piece.vertex_ids[v]];
        if (slot == UINT32_MAX) {
          slot = static_cast<std::uint32_t>(m.positions.size());
          m.positions.push_back(to_local(piece.mesh.world_position(v), m.origin));
          m.sensor_positions.push_back(to_local(piece.mesh.world_sensor_position(v), m.origin));
          if (intensities) m.intensities.push_back(piece.mesh.intensities[v]);
          if (colors) m.colors.push_back(piece.mesh.colors[v]);
        }
        tri[c] = slot;
      }
      m.triangles.push_back(tri);
      m.triangle_ids.push_back(piece.mesh.triangle_ids[t]);
      out.source_acq.push_back(static_cast<std::int32_t>(a));
      out.source_triangle.push_back(static_cast<std::int32_t>(index));
    }
    std::vector<std::pair<std::uint32_t, std::uint32_t>>().swap(order);
  }
  std::vector<TilePiece>().swap(pieces_);
  return out;
}

void TileAssembly::check_labelled() const {
  if (!labels_) throw ProcessingError("tile assembly: labels were not gathered");
  if (owned_ != index_.size()) {
    throw ProcessingError(
        fmt::format("tile assembly: {} triangles owned by the tiles, the input has {}", owned_, index_.size()));
  }
}

ChangeResult TileAssembly::labels(std::size_t k, std::uint64_t begin, std::uint64_t end) const {
  check_labelled();
  const std::vector<LabelSpill::Label> read =
      labels_->read(static_cast<std::uint32_t>(k), triangle_count(k), begin, end);
  const std::size_t n = read.size();
  ChangeResult c;
  c.index.offsets = {0, n};
  c.state.resize(n);
  c.first_seen.resize(n);
  c.last_seen.resize(n);
  c.sustainable.resize(n);
  c.kept.resize(n);
  c.refutes.resize(n);
  for (std::size_t t = 0; t < n; ++t) {
    const std::uint8_t f = read[t].flags;
    c.state[t] = static_cast<TriangleState>(f & kStateMask);
    c.kept[t] = (f & kKeptBit) != 0 ? 1 : 0;
    c.sustainable[t] = (f & kSustainableBit) != 0 ? 1 : 0;
    c.refutes[t] = (f & kRefutesBit) != 0 ? 1 : 0;
    // check_labelled(): every triangle was labelled, so dates_ms_ holds its dates.
    c.first_seen[t] = TimePoint(Duration(dates_ms_[read[t].first]));
    c.last_seen[t] = TimePoint(Duration(dates_ms_[read[t].last]));
  }
  // Raised by tiles where the triangle is a copy (TileResult::refuted).
  for (const std::uint32_t t : labels_->refuted(static_cast<std::uint32_t>(k), triangle_count(k), begin, end)) {
    c.refutes[t - begin] = 1;
  }
  c.stats.triangles = n;
  return c;
}

std::uint64_t TileAssembly::write_pairs(const std::filesystem::path& path, std::string_view magic) const {
  check_labelled();
  return pairs_->write_sorted(path, magic);
}

}  // namespace citymesh::app
