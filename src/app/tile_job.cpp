// SPDX-License-Identifier: MIT
#include "tile_job.h"

#include <algorithm>
#include <functional>
#include <unordered_map>

#include "citymesh/core/checksum.h"
#include "citymesh/core/process_memory.h"
#include "citymesh/core/stopwatch.h"
#include "citymesh/mosaic/mosaic.h"
#include "tile_plan.h"

namespace citymesh::app {

namespace {

/// Sorts [first, last) by `less` unless it is in order already: what the tile job sorts
/// mostly comes in order, and a check costs one pass where a sort costs several.
template <class It, class Less = std::less<>>
void sort_unless_sorted(It first, It last, Less less = {}) {
  if (!std::is_sorted(first, last, less)) std::sort(first, last, less);
}

MosaicSelection select(const Config& config, const std::vector<Mesh>& meshes, const std::vector<TimePoint>& dates,
                       const ChangeResult& change, std::span<const std::uint8_t> forced, bool least_memory) {
  const MosaicInput in{meshes, dates, &change, config.change.distance_threshold, forced, least_memory};
  return config.mosaic.method == MosaicMethod::update_model ? select_update_model(in)
                                                            : select_mosaic(in, config.mosaic);
}

/// Whether tile `key` is estimated above the memory budget: it runs alone (the tile stage's
/// gate), and its mosaic solves with the least memory (MosaicInput::least_memory: a spinning
/// street's largest tile 2.08 -> 1.82 GB, its mosaic 26.4 -> 29.6 s on 2 threads).
bool over_budget(const TileStore& store, TileKey key, const Config& config) {
  const TileContents* tile = store.find(key);
  return tile != nullptr && tile_over_budget(*tile, config.run.memory);
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

/// Empty-space copies lie outside the tile and its halo: they only bring their empty space,
/// and are never mosaic candidates (detect_changes does not keep them).
TriangleUse use_of(TileRole role) {
  switch (role) {
    case TileRole::owned:
      return TriangleUse::labelled;
    case TileRole::halo:
      return TriangleUse::context;
    default:
      return TriangleUse::empty_space;
  }
}

/// What `settled` says of the tile's halo triangles, in the tile's order: the only part of
/// it that the tile job reads.
std::uint64_t settled_fingerprint(std::span<const TilePiece> pieces, const SettledSelection& settled) {
  std::vector<std::uint8_t> answers;  // per halo triangle: 0 undecided, 1 not selected, 2 selected
  for (std::uint32_t a = 0; a < pieces.size(); ++a) {
    for (std::size_t t = 0; t < pieces[a].roles.size(); ++t) {
      if (pieces[a].roles[t] != TileRole::halo) continue;
      const std::optional<bool> selected = settled.selected(a, pieces[a].triangle_index[t]);
      answers.push_back(!selected ? 0 : *selected ? 2 : 1);
    }
  }
  return bulk_checksum(answers.data(), answers.size());
}

}  // namespace

std::uint64_t tile_settled_fingerprint(const TileStore& store, TileKey key, const SettledSelection& settled) {
  return settled_fingerprint(read_tile(store, key), settled);
}

bool keep_if_still_right(const std::filesystem::path& file, const TileStore& store, TileKey key, ResultDigests digests,
                         const SettledSelection& settled) {
  const std::optional<ResultOrigin> origin = tile_result_origin(file);
  if (!origin || origin->inputs != digests.inputs) return false;
  if (origin->settled != tile_settled_fingerprint(store, key, settled)) return false;
  const TileContents* tile = store.find(key);
  return tile != nullptr && restamp_tile_result(file, store, *origin, digests.result, tile->passes());
}

bool by_triangle(const OwnedLabel& x, const OwnedLabel& y) {
  return std::pair{x.acquisition, x.index} < std::pair{y.acquisition, y.index};
}

void SettledSelection::add(std::span<const OwnedLabel> labels) {
  const auto middle = static_cast<std::ptrdiff_t>(keys_.size());
  keys_.reserve(keys_.size() + labels.size());
  for (const OwnedLabel& l : labels) {
    keys_.push_back(std::uint64_t{l.acquisition} << 33 | std::uint64_t{l.index} << 1 | (l.selected != 0 ? 1u : 0u));
  }
  sort_unless_sorted(keys_.begin() + middle, keys_.end());
  std::inplace_merge(keys_.begin(), keys_.begin() + middle, keys_.end());
}

std::optional<bool> SettledSelection::selected(std::uint32_t acquisition, std::uint32_t index) const {
  const std::uint64_t probe = std::uint64_t{acquisition} << 33 | std::uint64_t{index} << 1;
  const auto it = std::lower_bound(keys_.begin(), keys_.end(), probe);
  if (it == keys_.end() || (*it | 1u) != (probe | 1u)) return std::nullopt;
  return (*it & 1u) != 0;
}

namespace {

/// The consistent pairs and the pairs of layers of one pass with an owned end, as result
/// pairs; the change step's lists are let go. A tile keeps each acquisition's triangles in
/// input order, so each list comes out sorted as it was. Its bytes are counted before they
/// are written: a spinning scanner's tile holds 56 M pairs (0.3 GB as the result holds them),
/// and a list grown by doubling holds up to twice that while it moves.
LabelPairList owned_pairs(ChangeResult& change, std::span<const TilePiece> pieces) {
  const GlobalTriangles& index = change.index;
  const auto each_owned = [&](const auto& visit) {
    LabelPair previous{};
    for (const PackedPairs* pairs : {&change.consistent_pairs, &change.layer_pairs}) {
      std::uint32_t ag = 0;  // g's acquisition, found by walking: each list comes sorted by g
      for (const auto& [g, h] : *pairs) {
        while (g >= index.offsets[ag + 1]) ++ag;
        const std::uint32_t ah = index.acquisition_of(h);
        const std::size_t tg = g - index.offsets[ag], th = h - index.offsets[ah];
        if (pieces[ag].roles[tg] != TileRole::owned && pieces[ah].roles[th] != TileRole::owned) continue;
        auto x = std::pair{ag, pieces[ag].triangle_index[tg]}, y = std::pair{ah, pieces[ah].triangle_index[th]};
        if (y < x) std::swap(x, y);
        const LabelPair p{x.first, x.second, y.first, y.second};
        visit(previous, p);
        previous = p;
      }
    }
  };
  std::size_t bytes = 0;
  each_owned([&](const LabelPair& previous, const LabelPair& p) { bytes += LabelPairList::bytes_after(previous, p); });
  LabelPairList out;
  out.reserve(bytes);
  each_owned([&](const LabelPair&, const LabelPair& p) { out.push_back(p); });
  change.consistent_pairs = {};
  change.layer_pairs = {};
  return out;
}

}  // namespace

int tile_phase(TileKey key) { return (key.i & 1) * 2 + (key.j & 1); }

TileResult process_tile(const TileStore& store, TileKey key, const Config& config, const SettledSelection& settled) {
  Stopwatch clock;
  TileResult r;
  r.key = key;
  if (const TileContents* tile = store.find(key)) r.passes = tile->passes();
  std::vector<TilePiece> pieces = read_tile(store, key);
  std::vector<Mesh> meshes;
  std::vector<TimePoint> dates;
  std::vector<TriangleUse> uses;
  for (std::size_t a = 0; a < pieces.size(); ++a) {
    meshes.push_back(std::move(pieces[a].mesh));
    dates.push_back(config.acquisitions[a].time);
    r.triangles_in_tile += meshes.back().triangle_count();
    for (const TileRole role : pieces[a].roles) uses.push_back(use_of(role));
  }
  r.seconds_read = clock.restart();
  r.settled_fingerprint = settled_fingerprint(pieces, settled);
  ChangeResult change = detect_changes({meshes, dates, uses}, config.change);
  r.seconds_detect = clock.restart();
  // The change step's lists were made in pieces (per block, then sorted) that the mosaic's
  // arrays do not fit into: what it freed goes back once the tile holds half the budget.
  if (resident_bytes() > config.run.memory / 2) release_freed_memory();
  r.change = change.stats;
  std::vector<std::uint8_t> forced(change.index.size(), 0);
  for (std::uint32_t a = 0; a < pieces.size(); ++a) {
    for (std::size_t t = 0; t < pieces[a].roles.size(); ++t) {
      const std::size_t g = change.index.offsets[a] + t;
      if (pieces[a].roles[t] != TileRole::halo) continue;
      const std::optional<bool> selected = settled.selected(a, pieces[a].triangle_index[t]);
      if (!selected) continue;
      change.kept[g] = *selected ? 1 : 0;
      forced[g] = *selected ? 1 : 0;
    }
  }
  const MosaicSelection selection = select(config, meshes, dates, change, forced, over_budget(store, key, config));
  r.seconds_mosaic = clock.restart();
  // The allocator keeps what the mosaic freed (its energy and pair index: ~1 GB on a spinning
  // scanner's tile) in pieces the result's pair list, made next, does not fit: handed back when
  // that list would take the process past the budget (such a tile alone peaked at 2.58 GB
  // without this, 2.13 GB with it).
  const std::uint64_t pair_bytes =
      (change.consistent_pairs.size() + change.layer_pairs.size()) * LabelPairList::kBytesPerPair;
  if (resident_bytes() + pair_bytes > config.run.memory) release_freed_memory();

  std::size_t owned_count = 0;
  for (const TilePiece& p : pieces)
    owned_count += static_cast<std::size_t>(std::count(p.roles.begin(), p.roles.end(), TileRole::owned));
  r.labels.reserve(owned_count);
  for (std::uint32_t a = 0; a < pieces.size(); ++a) {
    for (std::size_t t = 0; t < pieces[a].roles.size(); ++t) {
      const std::size_t g = change.index.offsets[a] + t;
      if (pieces[a].roles[t] != TileRole::owned) {
        if (change.refutes[g] != 0) r.refuted.push_back({a, pieces[a].triangle_index[t]});
        continue;
      }
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
    // Only the roles and triangle indices are read from here on: the mesh goes before the
    // pairs are made, the largest list of the result.
    pieces[a].mesh = Mesh{};
    pieces[a].vertex_ids = {};
  }
  // A tile keeps each acquisition's triangles in input order, so the labels come sorted
  // already (sorting them was 1 % of a run).
  sort_unless_sorted(r.labels.begin(), r.labels.end(), by_triangle);
  sort_unless_sorted(r.refuted.begin(), r.refuted.end());
  r.pairs = owned_pairs(change, pieces);
  return r;
}

}  // namespace citymesh::app
