// SPDX-License-Identifier: MIT
#include "tile_job.h"

#include <fmt/format.h>

#include <algorithm>
#include <cstring>
#include <unordered_map>

#include "citymesh/core/atomic_file.h"
#include "citymesh/core/checksum.h"
#include "citymesh/core/error.h"
#include "citymesh/core/log.h"
#include "citymesh/core/read_file.h"
#include "citymesh/core/stopwatch.h"
#include "citymesh/mosaic/mosaic.h"

namespace citymesh::app {

namespace {

// Version 02: a version 01 result may have been cut short by a failing worker (fixed in
// parallel_workers); such folders are processed again rather than trusted.
// Version 03: the checksum is XXH3 (bulk_checksum) instead of FNV-1a.
// Version 04: each label carries the mosaic's notes (seen through, filled, left out by the
// fill) in what was padding; older results would read as "nothing noted".
constexpr char kMagic[8] = {'C', 'M', 'R', 'S', 'L', 'T', '0', '4'};

struct ResultHeader {
  char magic[8];
  std::uint64_t fingerprint;
  std::int32_t i, j;
  std::uint64_t labels, pairs, acquisitions, triangles_in_tile;
  double seconds_read, seconds_detect, seconds_mosaic;
};
static_assert(sizeof(ResultHeader) == 80);

MosaicSelection select(const Config& config, const std::vector<Mesh>& meshes, const std::vector<TimePoint>& dates,
                       const ChangeResult& change, std::span<const std::uint8_t> forced) {
  const MosaicInput in{meshes, dates, &change, config.change.distance_threshold, forced};
  return config.mosaic.method == MosaicMethod::update_model ? select_update_model(in)
                                                            : select_mosaic(in, config.mosaic);
}

/// The selected owned triangles of one piece, with only the vertices they use.
TilePiece selected_part(const TilePiece& piece, std::span<const std::uint8_t> selected) {
  TilePiece out;
  const Mesh& m = piece.mesh;
  out.mesh.origin = m.origin;
  std::unordered_map<std::uint32_t, std::uint32_t> local;
  for (std::size_t t = 0; t < piece.triangle_count(); ++t) {
    if (piece.roles[t] != TileRole::owned || selected[t] == 0) continue;
    Triangle tri{};
    for (std::size_t c = 0; c < 3; ++c) {
      const std::uint32_t v = m.triangles[t][c];
      const auto [it, added] = local.try_emplace(v, static_cast<std::uint32_t>(out.vertex_ids.size()));
      if (added) {
        out.vertex_ids.push_back(piece.vertex_ids[v]);
        append_vertex(m, v, out.mesh);
      }
      tri[c] = it->second;
    }
    out.mesh.triangles.push_back(tri);
    out.mesh.triangle_ids.push_back(m.triangle_ids[t]);
    out.triangle_index.push_back(piece.triangle_index[t]);
    out.roles.push_back(TileRole::owned);
  }
  return out;
}

}  // namespace

bool by_triangle(const OwnedLabel& x, const OwnedLabel& y) {
  return std::pair{x.acquisition, x.index} < std::pair{y.acquisition, y.index};
}

int tile_phase(TileKey key) { return (key.i & 1) * 2 + (key.j & 1); }

TileResult process_tile(const TileStore& store, TileKey key, const Config& config,
                        std::span<const OwnedLabel> settled) {
  Stopwatch clock;
  TileResult r;
  r.key = key;
  std::vector<TilePiece> pieces = read_tile(store, key);
  std::vector<Mesh> meshes;
  std::vector<TimePoint> dates;
  for (std::size_t a = 0; a < pieces.size(); ++a) {
    meshes.push_back(std::move(pieces[a].mesh));
    dates.push_back(config.acquisitions[a].time);
    r.triangles_in_tile += meshes.back().triangle_count();
  }
  r.seconds_read = clock.restart();
  ChangeResult change = detect_changes({meshes, dates}, config.change);
  r.seconds_detect = clock.restart();
  std::vector<std::uint8_t> forced(change.index.size(), 0);
  for (std::uint32_t a = 0; a < pieces.size(); ++a) {
    for (std::size_t t = 0; t < pieces[a].roles.size(); ++t) {
      const std::size_t g = change.index.offsets[a] + t;
      // Empty-space triangles lie outside the tile and its halo: never mosaic candidates.
      if (pieces[a].roles[t] == TileRole::empty_space) change.kept[g] = 0;
      if (pieces[a].roles[t] != TileRole::halo) continue;
      const OwnedLabel probe{.acquisition = a, .index = pieces[a].triangle_index[t]};
      const auto it = std::lower_bound(settled.begin(), settled.end(), probe, by_triangle);
      if (it == settled.end() || it->acquisition != a || it->index != probe.index) continue;
      change.kept[g] = it->selected;
      forced[g] = it->selected;
    }
  }
  const MosaicSelection selection = select(config, meshes, dates, change, forced);
  r.seconds_mosaic = clock.restart();

  const auto owned = [&](std::uint32_t g) {
    const std::uint32_t a = change.index.acquisition_of(g);
    return pieces[a].roles[g - change.index.offsets[a]] == TileRole::owned;
  };
  const auto id = [&](std::uint32_t g) {
    const std::uint32_t a = change.index.acquisition_of(g);
    return std::pair{a, pieces[a].triangle_index[g - change.index.offsets[a]]};
  };
  for (std::uint32_t a = 0; a < pieces.size(); ++a) {
    for (std::size_t t = 0; t < pieces[a].roles.size(); ++t) {
      if (pieces[a].roles[t] != TileRole::owned) continue;
      const std::size_t g = change.index.offsets[a] + t;
      r.labels.push_back({.acquisition = a,
                          .index = pieces[a].triangle_index[t],
                          .state = change.state[g],
                          .kept = change.kept[g],
                          .sustainable = change.sustainable[g],
                          .refutes = change.refutes[g],
                          .selected = selection.selected[g],
                          .notes = selection.notes.empty() ? std::uint8_t{0} : selection.notes[g],
                          .first_ms = change.first_seen[g].time_since_epoch().count(),
                          .last_ms = change.last_seen[g].time_since_epoch().count()});
    }
    pieces[a].mesh = std::move(meshes[a]);
    r.selected.push_back(selected_part(
        pieces[a], std::span(selection.selected).subspan(change.index.offsets[a], pieces[a].triangle_count())));
  }
  std::sort(r.labels.begin(), r.labels.end(), by_triangle);
  for (const auto& [g, h] : change.consistent_pairs) {
    if (!owned(g) && !owned(h)) continue;
    auto x = id(g), y = id(h);
    if (y < x) std::swap(x, y);
    r.pairs.push_back({x.first, x.second, y.first, y.second});
  }
  std::sort(r.pairs.begin(), r.pairs.end(), [](const LabelPair& x, const LabelPair& y) {
    return std::tie(x.a_acquisition, x.a_index, x.b_acquisition, x.b_index) <
           std::tie(y.a_acquisition, y.a_index, y.b_acquisition, y.b_index);
  });
  return r;
}

void write_tile_result(const std::filesystem::path& file, const TileResult& r, std::uint64_t fingerprint) {
  ResultHeader h{};
  std::memcpy(h.magic, kMagic, sizeof kMagic);
  h.fingerprint = fingerprint;
  h.i = r.key.i;
  h.j = r.key.j;
  h.labels = r.labels.size();
  h.pairs = r.pairs.size();
  h.acquisitions = r.selected.size();
  h.triangles_in_tile = r.triangles_in_tile;
  h.seconds_read = r.seconds_read;
  h.seconds_detect = r.seconds_detect;
  h.seconds_mosaic = r.seconds_mosaic;
  std::string bytes(reinterpret_cast<const char*>(&h), sizeof h);
  bytes.append(reinterpret_cast<const char*>(r.labels.data()), r.labels.size() * sizeof(OwnedLabel));
  bytes.append(reinterpret_cast<const char*>(r.pairs.data()), r.pairs.size() * sizeof(LabelPair));
  for (const TilePiece& p : r.selected) {
    const std::string block = p.triangle_count() == 0 ? std::string() : encode_tile_block(p);
    const std::uint64_t size = block.size();
    bytes.append(reinterpret_cast<const char*>(&size), sizeof size);
    bytes += block;
  }
  const std::uint64_t sum = bulk_checksum(bytes.data(), bytes.size());
  bytes.append(reinterpret_cast<const char*>(&sum), sizeof sum);
  write_file_atomically(file, bytes);
}

std::optional<TileResult> read_tile_result(const std::filesystem::path& file, std::uint64_t fingerprint,
                                           const TileStore& store) {
  const std::optional<std::string> read = read_file_bytes(file);
  if (!read) return std::nullopt;
  const std::string& bytes = *read;
  ResultHeader h{};
  std::uint64_t sum = 0;
  const auto stale = [&](std::string_view why) -> std::optional<TileResult> {
    log::warn("{}: {}; the tile is processed again", file.string(), why);
    return std::nullopt;
  };
  if (bytes.size() < sizeof h + sizeof sum) return stale("truncated");
  std::memcpy(&sum, bytes.data() + bytes.size() - sizeof sum, sizeof sum);
  if (bulk_checksum(bytes.data(), bytes.size() - sizeof sum) != sum) return stale("checksum mismatch");
  std::memcpy(&h, bytes.data(), sizeof h);
  if (std::memcmp(h.magic, kMagic, sizeof kMagic) != 0) return stale("not a tile result");
  if (h.fingerprint != fingerprint) return std::nullopt;  // made with another config: --force was given
  const std::size_t body = bytes.size() - sizeof sum - sizeof h;
  if (h.acquisitions != store.triangles.size() || h.labels > body / sizeof(OwnedLabel) ||
      h.pairs > body / sizeof(LabelPair) || h.labels * sizeof(OwnedLabel) + h.pairs * sizeof(LabelPair) > body) {
    return stale("counts do not fit");
  }
  TileResult r;
  r.key = {h.i, h.j};
  r.triangles_in_tile = h.triangles_in_tile;
  r.seconds_read = h.seconds_read;
  r.seconds_detect = h.seconds_detect;
  r.seconds_mosaic = h.seconds_mosaic;
  std::size_t at = sizeof h;
  r.labels.resize(h.labels);
  std::memcpy(static_cast<void*>(r.labels.data()), bytes.data() + at, h.labels * sizeof(OwnedLabel));
  at += h.labels * sizeof(OwnedLabel);
  r.pairs.resize(h.pairs);
  std::memcpy(static_cast<void*>(r.pairs.data()), bytes.data() + at, h.pairs * sizeof(LabelPair));
  at += h.pairs * sizeof(LabelPair);
  const Vec3d origin = TileGrid(store.grid).corner(r.key);
  for (std::uint32_t a = 0; a < h.acquisitions; ++a) {
    std::uint64_t size = 0;
    if (bytes.size() - sizeof sum - at < sizeof size) return stale("truncated");
    std::memcpy(&size, bytes.data() + at, sizeof size);
    at += sizeof size;
    if (size > bytes.size() - sizeof sum - at) return stale("truncated");
    TilePiece piece;
    piece.mesh.origin = origin;
    if (size > 0) piece = decode_tile_blocks(std::string_view(bytes).substr(at, size), origin, a, file.string());
    r.selected.push_back(std::move(piece));
    at += size;
  }
  return r;
}

}  // namespace citymesh::app
