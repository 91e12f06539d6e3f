// SPDX-License-Identifier: MIT
// The seam pass in files: parts written and read back whole (damaged ones refused), tiles
// filed under their parts whatever the tiling, and stitching from files giving what
// stitching in memory gives.
#include "seam_parts.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <map>
#include <set>

#include "../mosaic/stitch_fixtures.h"
#include "citymesh/core/error.h"
#include "face_table.h"
#include "leaf_outputs.h"
#include "seam_cache.h"
#include "test_support.h"

namespace citymesh::app {
namespace {

const StitchParams kParams{.snap = 0.02, .reach = 0.2, .weld = 0.005, .clip = 0.1, .gap = 0.025};

/// Blocks of 1.6 m with bands of 0.35 m, the grid's corner at (0.7, 0.7): every kind of part
/// holds seams of the four-source scene.
BlockStitchParams blocks() { return {.origin_x = 0.7, .origin_y = 0.7, .size = 1.6, .band = 0.35}; }

/// The triangles of `m` chosen by `keep` as a tile's selected pieces, one per source: vertex
/// ids are the mesh's vertex indices, triangle indices its source_triangle.
template <class Keep>
std::vector<TilePiece> tile_pieces(const MergedMesh& m, Keep keep) {
  std::map<std::int32_t, TilePiece> by_source;
  std::map<std::int32_t, std::map<std::uint32_t, std::uint32_t>> local;
  for (std::uint32_t t = 0; t < m.mesh.triangle_count(); ++t) {
    if (!keep(t)) continue;
    const std::int32_t s = m.source_acq[t];
    TilePiece& p = by_source[s];
    p.mesh.origin = m.mesh.origin;
    Triangle tri{};
    for (std::size_t k = 0; k < 3; ++k) {
      const std::uint32_t v = m.mesh.triangles[t][k];
      const auto [it, added] = local[s].try_emplace(v, static_cast<std::uint32_t>(p.vertex_ids.size()));
      if (added) {
        p.vertex_ids.push_back(v);
        append_vertex(m.mesh, v, p.mesh);
      }
      tri[k] = it->second;
    }
    p.mesh.triangles.push_back(tri);
    p.mesh.triangle_ids.push_back({.acquisition = static_cast<std::uint32_t>(s), .face = t});
    p.triangle_index.push_back(static_cast<std::uint32_t>(m.source_triangle[t]));
    p.roles.push_back(TileRole::owned);
  }
  std::vector<TilePiece> out;
  for (auto& [s, p] : by_source) out.push_back(std::move(p));
  return out;
}

/// The stitched parts as one mesh (vertices in key order, floats relative to the first in
/// whole metres, triangles part by part): the whole output, to compare against.
MergedMesh gather_stitched_parts(std::span<const BlockPart> parts, const PartStore& store) {
  // First every key, then each part's vertices and triangles in place: the output and one
  // part in memory, never every part at once.
  std::vector<std::uint64_t> keys;
  for (std::size_t p = 0; p < parts.size(); ++p) {
    const std::shared_ptr<const KeyedPiece> piece = store.load(p, true);
    keys.insert(keys.end(), piece->keys.begin(), piece->keys.end());
  }
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  MergedMesh out;
  Mesh& m = out.mesh;
  bool first = true;
  std::vector<std::uint8_t> placed(keys.size(), 0);
  for (std::size_t p = 0; p < parts.size(); ++p) {
    const std::shared_ptr<const KeyedPiece> piece = store.load(p, true);
    if (piece->vertex_count() == 0) continue;
    if (first) {
      m.origin = whole_metre_origin(piece->positions.front());
      m.positions.resize(keys.size());
      if (!piece->sensors.empty()) m.sensor_positions.resize(keys.size());
      if (!piece->times.empty()) m.times.resize(keys.size());
      if (!piece->intensities.empty()) m.intensities.resize(keys.size());
      if (!piece->colors.empty()) m.colors.resize(keys.size());
      first = false;
    }
    std::vector<std::uint32_t> index(piece->vertex_count());
    std::size_t at = 0;
    for (std::size_t v = 0; v < index.size(); ++v) {
      while (keys[at] != piece->keys[v]) ++at;  // both ascend
      index[v] = static_cast<std::uint32_t>(at);
      if (placed[at] != 0) continue;
      placed[at] = 1;
      m.positions[at] = to_local(piece->positions[v], m.origin);
      if (!m.sensor_positions.empty()) m.sensor_positions[at] = to_local(piece->sensors[v], m.origin);
      if (!m.times.empty()) m.times[at] = piece->times[v];
      if (!m.intensities.empty()) m.intensities[at] = piece->intensities[v];
      if (!m.colors.empty()) m.colors[at] = piece->colors[v];
    }
    for (std::size_t t = 0; t < piece->triangle_count(); ++t) {
      const Triangle& tri = piece->triangles[t];
      m.triangles.push_back({index[tri[0]], index[tri[1]], index[tri[2]]});
      m.triangle_ids.push_back(piece->ids[t]);
      out.source_acq.push_back(piece->source_acq[t]);
      out.source_triangle.push_back(piece->source_triangle[t]);
    }
  }
  return out;
}

KeyedPiece sample_piece() {
  KeyedPiece p;
  p.keys = {3, input_vertex_key(2, 7), kNewVertexKey | 5};
  p.positions = {{651000.25, 6861000.5, 35.125}, {651001.0, 6861000.0, 35.0}, {651000.0, 6861001.0, 36.0}};
  p.sensors = {{651005.0, 6861000.0, 37.5}, {651005.0, 6861000.1, 37.5}, {651005.0, 6861000.2, 37.5}};
  p.intensities = {0.5f, 0.25f, 1.0f};
  p.colors = {{1, 2, 3}, {4, 5, 6}, {7, 8, 9}};
  p.triangles = {{0, 1, 2}};
  p.ids = {{.acquisition = 2, .fan = 1, .face = 1234567890123}};
  p.source_acq = {2};
  p.source_triangle = {42};
  return p;
}

TEST(SeamParts, APieceComesBackFromItsBytesAsItWent) {
  const KeyedPiece p = sample_piece();
  const KeyedPiece q = decode_keyed_piece(encode_keyed_piece(p), "sample");
  EXPECT_EQ(q.keys, p.keys);
  EXPECT_EQ(q.positions, p.positions);
  EXPECT_EQ(q.sensors, p.sensors);
  EXPECT_TRUE(q.times.empty());
  EXPECT_EQ(q.intensities, p.intensities);
  EXPECT_EQ(q.colors, p.colors);
  EXPECT_EQ(q.triangles, p.triangles);
  EXPECT_EQ(q.ids, p.ids);
  EXPECT_EQ(q.source_acq, p.source_acq);
  EXPECT_EQ(q.source_triangle, p.source_triangle);
}

TEST(SeamParts, DamagedPiecesAreRefusedNamingTheFile) {
  const std::string bytes = encode_keyed_piece(sample_piece());
  const auto refused = [](const std::string& damaged) {
    try {
      (void)decode_keyed_piece(damaged, "parts/0_1_2.input.part");
    } catch (const ProcessingError& e) {
      return std::string(e.what()).find("parts/0_1_2.input.part") != std::string::npos;
    }
    return false;
  };
  EXPECT_TRUE(refused(bytes.substr(0, bytes.size() - 1)));  // truncated
  EXPECT_TRUE(refused(bytes.substr(0, 20)));                // not even a header
  std::string flipped = bytes;
  flipped[flipped.size() - 3] ^= 0x10;  // the payload: the checksum no longer matches
  EXPECT_TRUE(refused(flipped));
  std::string magic = bytes;
  magic[0] = 'X';
  EXPECT_TRUE(refused(magic));
  std::string counts = bytes;
  counts[16] = '\x7f';  // a vertex count far beyond the file: refused before any allocation
  EXPECT_TRUE(refused(counts));
}

TEST(SeamParts, TilesAreFiledUnderTheirPartsWhateverTheTiling) {
  const MergedMesh m = test::four_source_scene();
  test::TempDir dir;
  SeamPartFiles one(dir / "one", blocks()), two(dir / "two", blocks());
  one.add_tile({0, 0}, tile_pieces(m, [](std::uint32_t) { return true; }));
  // Cut along x = 1.5: triangles on both sides share vertices, which must come out once.
  const auto west = [&](std::uint32_t t) { return m.mesh.positions[m.mesh.triangles[t][0]].x < 1.5f; };
  // As the final pass reads results: filed in any order (threads), added in tile order.
  const SeamPartFiles::FiledTile east_filed =
      two.file_tile({1, 0}, tile_pieces(m, [&](std::uint32_t t) { return !west(t); }));
  const SeamPartFiles::FiledTile west_filed = two.file_tile({0, 0}, tile_pieces(m, west));
  EXPECT_TRUE(std::is_sorted(west_filed.parts.begin(), west_filed.parts.end()));
  two.add_filed(west_filed);
  two.add_filed(east_filed);
  const std::vector<BlockPart> a = one.finish(), b = two.finish();
  ASSERT_EQ(a.size(), b.size());
  EXPECT_GT(a.size(), 9u);
  EXPECT_EQ(one.source_sizes(), two.source_sizes());
  std::size_t triangles = 0;
  for (std::size_t p = 0; p < a.size(); ++p) {
    EXPECT_EQ(a[p].key, b[p].key);
    const auto x = one.load(p, false), y = two.load(p, false);
    EXPECT_EQ(x->keys, y->keys);
    EXPECT_EQ(x->positions, y->positions);
    EXPECT_EQ(x->triangles, y->triangles);
    EXPECT_EQ(x->source_triangle, y->source_triangle);
    // In input order, each in the part holding its centroid.
    for (std::size_t t = 0; t < x->triangle_count(); ++t) {
      if (t > 0) {
        EXPECT_LT(std::pair(x->source_acq[t - 1], x->source_triangle[t - 1]),
                  std::pair(x->source_acq[t], x->source_triangle[t]));
      }
      const Triangle& tri = x->triangles[t];
      const Vec3d c = (x->positions[tri[0]] + x->positions[tri[1]] + x->positions[tri[2]]) / 3.0;
      EXPECT_EQ(block_part_of(c, blocks()), a[p].key);
    }
    triangles += x->triangle_count();
  }
  EXPECT_EQ(triangles, m.mesh.triangle_count());
}

TEST(SeamParts, StitchingFromFilesGivesWhatStitchingInMemoryGives) {
  MergedMesh in_memory = test::four_source_scene();
  const BlockStitchStats expected = stitch_in_blocks(in_memory, kParams, blocks());

  test::TempDir dir;
  SeamPartFiles files(dir / "seams", blocks());
  files.add_tile({0, 0}, tile_pieces(test::four_source_scene(), [](std::uint32_t) { return true; }));
  std::vector<BlockPart> parts = files.finish();
  PartStitchRun run{
      .params = kParams, .blocks = blocks(), .source_sizes = files.source_sizes(), .frame = Vec3d{}, .run_level = {}};
  run.blocks.context = block_context(kParams);
  const double before = parts_open_boundary(parts, files, false, run.blocks);
  const BlockStitchStats s = stitch_parts(parts, files, run);
  const double after = parts_open_boundary(parts, files, true, run.blocks);
  const MergedMesh out = gather_stitched_parts(parts, files);

  EXPECT_EQ(s.parts, expected.parts);
  EXPECT_EQ(s.stitch.strips, expected.stitch.strips);
  EXPECT_EQ(s.stitch.vertices_snapped, expected.stitch.vertices_snapped);
  EXPECT_NEAR(before, expected.stitch.open_boundary_before, 1e-6);
  EXPECT_NEAR(after, expected.stitch.open_boundary_after, 1e-6);
  ASSERT_EQ(out.mesh.triangle_count(), in_memory.mesh.triangle_count());
  for (std::size_t t = 0; t < out.mesh.triangle_count(); ++t) {
    ASSERT_EQ(out.source_acq[t], in_memory.source_acq[t]) << t;
    ASSERT_EQ(out.source_triangle[t], in_memory.source_triangle[t]) << t;
    for (std::size_t k = 0; k < 3; ++k) {
      const Vec3d p = out.mesh.world_position(out.mesh.triangles[t][k]);
      const Vec3d q = in_memory.mesh.world_position(in_memory.mesh.triangles[t][k]);
      ASSERT_LT(norm(p - q), 1e-6) << "triangle " << t << " corner " << k;
    }
  }
  EXPECT_EQ(test::non_manifold_edges(out.mesh), 0u);
}

/// The triangles of an output as (corner positions, source) triples, whatever its numbering.
std::multiset<std::array<double, 10>> geometry(std::span<const Vec3d> positions, std::span<const Triangle> triangles,
                                               std::span<const double> sources) {
  std::multiset<std::array<double, 10>> out;
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    std::array<double, 10> row{};
    for (std::size_t k = 0; k < 3; ++k) {
      const Vec3d& p = positions[triangles[t][k]];
      row[3 * k] = p.x;
      row[3 * k + 1] = p.y;
      row[3 * k + 2] = p.z;
    }
    row[9] = sources[t];
    out.insert(row);
  }
  return out;
}

TEST(SeamParts, TheOutputWrittenTileByTileIsTheGatheredOutputWithEachVertexOnce) {
  test::TempDir dir;
  SeamPartFiles files(dir / "seams", blocks());
  files.add_tile({0, 0}, tile_pieces(test::four_source_scene(), [](std::uint32_t) { return true; }));
  std::vector<BlockPart> parts = files.finish();
  PartStitchRun run{.params = kParams,
                    .blocks = blocks(),
                    .source_sizes = files.source_sizes(),
                    .frame = std::nullopt,
                    .run_level = {}};
  (void)stitch_parts(parts, files, run);
  const MergedMesh gathered = gather_stitched_parts(parts, files);
  // Tiles of 1 m: vertices shared by up to four tiles, some by tiles that meet at a corner only.
  const OutputLeaves leaves(dir / "tiles", TileGrid({.tile_size = 1.0, .halo = 0.1, .origin = {0.3, 0.3}}), parts,
                            files);
  EXPECT_GT(leaves.leaves().size(), 12u);
  // The config lists the four sources in another order than the one they are processed in:
  // the PLY names each by its place in the file.
  const std::vector<std::int32_t> listed{2, 0, 3, 1};
  write_leaves_ply(dir / "mosaic.ply", leaves, listed);

  const FaceTable written = read_face_table(dir / "mosaic.ply", {"source_acq", "source_face"});
  EXPECT_EQ(written.positions.size(), gathered.mesh.vertex_count()) << "each vertex once";
  // The positions as the parts hold them, exactly (the gathered mesh has floats).
  std::multiset<std::array<double, 10>> expected;
  for (std::size_t p = 0; p < parts.size(); ++p) {
    const auto piece = files.load(p, true);
    std::vector<double> sources;
    for (const std::int32_t a : piece->source_acq)
      sources.push_back(a < 0 ? a : listed.at(static_cast<std::size_t>(a)));
    expected.merge(geometry(piece->positions, piece->triangles, sources));
  }
  EXPECT_EQ(geometry(written.positions, written.triangles, written.extras[0]), expected);
  Mesh as_mesh = written.local_mesh(Vec3d{});
  EXPECT_EQ(test::non_manifold_edges(as_mesh), 0u);
  EXPECT_EQ(test::non_manifold_edges(as_mesh), test::non_manifold_edges(gathered.mesh));
  EXPECT_EQ(open_boundary_length(as_mesh) > 0, true);
  EXPECT_NEAR(open_boundary_length(as_mesh), open_boundary_length(gathered.mesh), 1e-3);
  std::uint64_t counted = leaves.stitched();
  for (const std::uint64_t n : leaves.per_source()) counted += n;
  EXPECT_EQ(counted, gathered.mesh.triangle_count());
}

/// Triangle t's centroid in the frame of the parts (the scene's world positions).
Vec3d centroid_of(const MergedMesh& m, std::uint32_t t) {
  Vec3d c{};
  for (const std::uint32_t v : m.mesh.triangles[t]) c = c + m.mesh.world_position(v) * (1.0 / 3.0);
  return c;
}

/// The four-source scene without the triangles `drop` names, stitched from files (cache:
/// optional), the cache pruned to what this run used; the output gathered.
struct CachedStitch {
  MergedMesh out;
  BlockStitchStats stats;
  std::size_t parts = 0;
};
template <class Drop>
CachedStitch stitch_scene(const test::TempDir& dir, const std::string& name, Drop drop, SeamPartCache* cache,
                          const MergedMesh& scene = test::four_source_scene()) {
  SeamPartFiles files(dir / name, blocks());
  files.add_tile({0, 0}, tile_pieces(scene, [&](std::uint32_t t) { return !drop(scene, t); }));
  std::vector<BlockPart> parts = files.finish();
  const PartStitchRun run{.params = kParams,
                          .blocks = blocks(),
                          .source_sizes = files.source_sizes(),
                          .frame = std::nullopt,
                          .run_level = {},
                          .cache = cache};
  CachedStitch r;
  r.stats = stitch_parts(parts, files, run);
  if (cache != nullptr) cache->prune(parts, r.stats.digests);
  r.out = gather_stitched_parts(parts, files);
  r.parts = parts.size();
  return r;
}

void expect_same_output(const MergedMesh& a, const MergedMesh& b) {
  ASSERT_EQ(a.mesh.triangle_count(), b.mesh.triangle_count());
  EXPECT_EQ(a.mesh.triangles, b.mesh.triangles);
  EXPECT_EQ(a.mesh.positions, b.mesh.positions);
  EXPECT_EQ(a.source_acq, b.source_acq);
  EXPECT_EQ(a.source_triangle, b.source_triangle);
}

std::size_t files_in(const std::filesystem::path& dir) {
  std::size_t n = 0;
  for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator(dir)) ++n;
  return n;
}

TEST(SeamCache, PartsWhoseInputsChangedAreStitchedAgainTheOthersTakenToTheSameOutput) {
  test::TempDir dir;
  const auto none = [](const MergedMesh&, std::uint32_t) { return false; };
  // A hole in source 0 inside one block's interior: that block's stitched output changes,
  // so the parts of later levels around it, which see it as done, are stitched again too; no
  // part appears or goes, so every other part keeps its place in the list.
  const auto hole = [](const MergedMesh& m, std::uint32_t t) {
    Vec3f c{};
    for (const std::uint32_t v : m.mesh.triangles[t]) c = c + m.mesh.positions[v] * (1.f / 3.f);
    return m.source_acq[t] == 0 && c.x > 1.2f && c.x < 1.8f && c.y > 1.1f && c.y < 1.25f;
  };
  SeamPartCache cache(dir / "cache", 7);
  const CachedStitch plain = stitch_scene(dir, "plain", none, nullptr);
  const CachedStitch first = stitch_scene(dir, "first", none, &cache);
  EXPECT_EQ(first.stats.reused_parts, 0u);
  expect_same_output(first.out, plain.out);
  EXPECT_EQ(files_in(dir / "cache"), first.parts);

  const CachedStitch again = stitch_scene(dir, "again", none, &cache);
  EXPECT_EQ(again.stats.reused_parts, again.parts);
  expect_same_output(again.out, plain.out);
  EXPECT_EQ(again.stats.stitch.strips, plain.stats.stitch.strips);
  EXPECT_EQ(again.stats.stitch.vertices_snapped, plain.stats.stitch.vertices_snapped);
  EXPECT_EQ(again.stats.largest_part, plain.stats.largest_part);

  const CachedStitch changed_plain = stitch_scene(dir, "changed-plain", hole, nullptr);
  const CachedStitch changed = stitch_scene(dir, "changed", hole, &cache);
  ASSERT_EQ(changed.parts, first.parts);
  EXPECT_GT(changed.stats.reused_parts, 0u);
  EXPECT_LT(changed.stats.reused_parts + 1, changed.parts) << "the block and the parts that see it done";
  expect_same_output(changed.out, changed_plain.out);
  EXPECT_EQ(files_in(dir / "cache"), changed.parts) << "pruned to what the last run used";

  // A damaged entry is stitched again, not read.
  const auto victim = std::filesystem::directory_iterator(dir / "cache")->path();
  {
    std::fstream f(victim, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(static_cast<std::streamoff>(std::filesystem::file_size(victim) / 2));
    f.put('\x5a');
  }
  const CachedStitch mended = stitch_scene(dir, "mended", hole, &cache);
  EXPECT_EQ(mended.stats.reused_parts, mended.parts - 1);
  expect_same_output(mended.out, changed_plain.out);

  // Other settings: nothing of the earlier runs is theirs.
  SeamPartCache other(dir / "cache", 8);
  EXPECT_EQ(stitch_scene(dir, "other", hole, &other).stats.reused_parts, 0u);
}

TEST(SeamCache, PartsAreReusedWhenAPartAppearsOrGoesBeforeThemInTheList) {
  // The first part of the list (the block interior with the smallest key) emptied, then
  // filled again: every later part moves one place in the list, and the new vertices of the
  // parts stitched before them are named after their index. Parts away from it are reused
  // all the same, and the output is that of stitching without the cache.
  test::TempDir dir;
  const auto none = [](const MergedMesh&, std::uint32_t) { return false; };
  // Source 2 with another spacing than source 0's beside it: snapping splits their edges.
  MergedMesh scene;
  test::add_grid(scene, 0, 0, 30, 30, 0.1f, 0, 0);
  test::add_grid(scene, 3.015f, 0.013f, 19, 23, 0.13f, 1, 0.01f);
  test::add_grid(scene, 0, 3.015f, 21, 12, 0.1428571f, 2, 0.01f);
  // Small pieces of source 3 half over source 0's side y = 0: clipping cuts them along it,
  // making new vertices in several parts.
  for (const float x0 : {0.15f, 1.05f, 2.05f, 2.55f}) test::add_grid(scene, x0, -0.33f, 4, 7, 0.1f, 3, 0.05f);
  BlockPartKey first{INT32_MAX, 0, 0};
  for (std::uint32_t t = 0; t < scene.mesh.triangle_count(); ++t) {
    first = std::min(first, block_part_of(centroid_of(scene, t), blocks()));
  }
  ASSERT_EQ(first.level, 0);
  const auto empty_first = [&](const MergedMesh& m, std::uint32_t t) {
    return block_part_of(centroid_of(m, t), blocks()) == first;
  };
  SeamPartCache cache(dir / "cache", 7);
  const CachedStitch whole = stitch_scene(dir, "whole", none, &cache, scene);
  const CachedStitch without_plain = stitch_scene(dir, "without-plain", empty_first, nullptr, scene);
  const CachedStitch without = stitch_scene(dir, "without", empty_first, &cache, scene);
  ASSERT_EQ(without.parts + 1, whole.parts) << "the first part is gone";
  ASSERT_GT(whole.stats.stitch.edges_split, 0u) << "new vertices";
  expect_same_output(without.out, without_plain.out);
  EXPECT_GT(without.stats.reused_parts, without.parts / 3) << "parts away from it";
  EXPECT_LT(without.stats.reused_parts, without.parts) << "its neighbours see it gone";

  const CachedStitch back_plain = stitch_scene(dir, "back-plain", none, nullptr, scene);
  const CachedStitch back = stitch_scene(dir, "back", none, &cache, scene);
  ASSERT_EQ(back.parts, whole.parts);
  expect_same_output(back.out, back_plain.out);
  EXPECT_GT(back.stats.reused_parts, back.parts / 3);
  EXPECT_LT(back.stats.reused_parts, back.parts);
}

TEST(SeamCache, PartsWhoseSourcesWereRenumberedAreReusedUnderTheNewNumbers) {
  // A pass delivered late, older than sources 1 to 3 but over none of this scene: they
  // become 2 to 4. Every part reads the same sources in the same order, so every part is
  // found (kept under the ranks of its sources), to the output of stitching the renumbered
  // scene without the cache; and back when the pass is removed again.
  test::TempDir dir;
  const auto none = [](const MergedMesh&, std::uint32_t) { return false; };
  const MergedMesh scene = test::four_source_scene();
  MergedMesh renumbered = scene;
  for (std::int32_t& s : renumbered.source_acq) s += s >= 1 ? 1 : 0;
  SeamPartCache cache(dir / "cache", 7);
  const CachedStitch first = stitch_scene(dir, "first", none, &cache, scene);
  ASSERT_EQ(first.stats.reused_parts, 0u);
  const CachedStitch late_plain = stitch_scene(dir, "late-plain", none, nullptr, renumbered);
  const CachedStitch late = stitch_scene(dir, "late", none, &cache, renumbered);
  EXPECT_EQ(late.stats.reused_parts, late.parts);
  expect_same_output(late.out, late_plain.out);
  std::set<std::int32_t> sources(late.out.source_acq.begin(), late.out.source_acq.end());
  EXPECT_TRUE(sources.contains(2) && sources.contains(3) && !sources.contains(1)) << "the renumbered sources, found";
  const CachedStitch back = stitch_scene(dir, "back", none, &cache, scene);
  EXPECT_EQ(back.stats.reused_parts, back.parts);
  expect_same_output(back.out, first.out);
  // Sources renumbered out of order (1 and 2 swapped) are another stitching: not found.
  MergedMesh swapped = scene;
  for (std::int32_t& s : swapped.source_acq) s = s == 1 ? 2 : s == 2 ? 1 : s;
  const CachedStitch other = stitch_scene(dir, "swapped", none, &cache, swapped);
  EXPECT_LT(other.stats.reused_parts, other.parts);
  expect_same_output(other.out, stitch_scene(dir, "swapped-plain", none, nullptr, swapped).out);
}

}  // namespace
}  // namespace citymesh::app
