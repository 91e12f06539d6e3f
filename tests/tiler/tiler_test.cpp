// SPDX-License-Identifier: MIT
#include "citymesh/tiler/tiler.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <functional>
#include <map>
#include <random>
#include <set>

#include "citymesh/core/error.h"
#include "citymesh/core/parallel.h"
#include "citymesh/io/mesh_io.h"
#include "citymesh/io/ply_writer.h"
#include "test_support.h"

namespace citymesh {
namespace {

/// A random soup of small triangles over 60 x 60 m at city coordinates, each vertex seen from
/// a sensor up to `reach` metres away in x and y, with intensities.
Mesh random_acquisition(std::uint32_t seed, std::size_t triangles, double reach = 20) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0, 60), d(-0.8, 0.8), far(-reach, reach);
  Mesh m;
  m.origin = {651000, 6860000, 30};
  for (std::size_t t = 0; t < triangles; ++t) {
    const Vec3d a{u(rng), u(rng), d(rng)};
    const Vec3d sensor = a + Vec3d{far(rng), far(rng), 3};
    const auto v = static_cast<std::uint32_t>(m.positions.size());
    for (const Vec3d& p : {a, a + Vec3d{d(rng), d(rng), 0.3}, a + Vec3d{d(rng), d(rng), 0}}) {
      m.positions.push_back(Vec3f(p));
      m.sensor_positions.push_back(Vec3f(sensor + Vec3d{d(rng), d(rng), 0}));
      m.intensities.push_back(float(t % 100));
    }
    // Every other triangle shares an edge with the previous one, so vertices are shared.
    if (t % 2 == 1) {
      m.triangles.push_back({v - 3, v - 2, v});
    } else {
      m.triangles.push_back({v, v + 1, v + 2});
    }
  }
  m.triangle_ids.resize(m.triangles.size());
  return m;
}

/// The triangles in rows 10 m high, each row by x: as scan lines come, runs of consecutive
/// triangles fall in one tile.
void sort_in_rows(Mesh& m) {
  const auto key = [&](const Triangle& t) {
    const Vec3f& p = m.positions[t[0]];
    return std::pair(std::floor(p.y / 10), p.x);
  };
  std::sort(m.triangles.begin(), m.triangles.end(),
            [&](const Triangle& a, const Triangle& b) { return key(a) < key(b); });
}

struct Fixture {
  test::TempDir tmp;
  std::vector<Mesh> meshes;
  std::vector<Acquisition> acquisitions;
  TilerParams params;

  /// `scan_order`: sensors within 3 m and the triangles in rows (sort_in_rows), so that most
  /// triangles lie, with their viewpoint, in the tile of the triangle before (otherwise
  /// consecutive triangles jump between tiles at random and most reach into other tiles).
  explicit Fixture(std::uint64_t buffer_bytes = 256ull << 20, bool scan_order = false) {
    for (std::uint32_t a = 0; a < 2; ++a) {
      meshes.push_back(random_acquisition(10 + a, 3000, scan_order ? 3 : 20));
      if (scan_order) sort_in_rows(meshes.back());
      const auto path = tmp / ("acq" + std::to_string(a) + ".ply");
      write_mesh_ply(path, meshes.back());
      acquisitions.push_back({a, TimePoint{}, path});
    }
    params.grid = {.tile_size = 20, .halo = 2, .origin = {651000, 6860000}};
    params.dir = tmp / "tiles";
    params.buffer_bytes = buffer_bytes;
  }
};

/// The counts in the header of the block at `at` of `file` (magic, version, flags, vertices,
/// triangles, payload bytes, checksum) and the block's whole size.
struct BlockCounts {
  std::uint64_t vertices = 0, triangles = 0, bytes = 0;
};
BlockCounts block_counts(const std::filesystem::path& file, const ByteRange& at) {
  std::ifstream in(file, std::ios::binary);
  in.seekg(static_cast<std::streamoff>(at.offset));
  std::array<std::uint64_t, 6> header{};  // 8 + 4 + 4 bytes of magic, version, flags first
  in.read(reinterpret_cast<char*>(header.data()), sizeof header);
  return {header[2], header[3], 48 + header[4]};
}

std::array<Vec3d, 3> world_corners(const Mesh& m, std::size_t t) {
  const Triangle& tri = m.triangles[t];
  return {m.world_position(tri[0]), m.world_position(tri[1]), m.world_position(tri[2])};
}

/// Expected role of every (acquisition, triangle) in every tile, by brute force from the grid.
std::map<std::pair<TileKey, std::pair<std::uint32_t, std::uint32_t>>, TileRole> expected_roles(const Fixture& f) {
  const TileGrid grid(f.params.grid);
  std::map<std::pair<TileKey, std::pair<std::uint32_t, std::uint32_t>>, TileRole> roles;
  for (std::uint32_t a = 0; a < f.meshes.size(); ++a) {
    const Mesh& m = f.meshes[a];
    for (std::uint32_t t = 0; t < m.triangle_count(); ++t) {
      const auto c = world_corners(m, t);
      Box3d box;
      for (const Vec3d& p : c) box.extend(p);
      const TileKey owner = grid.owner((c[0] + c[1] + c[2]) / 3.0);
      Vec3d view{0, 0, 0};
      for (const std::uint32_t v : m.triangles[t]) view = view + m.world_sensor_position(v) / 3.0;
      const std::array<Vec3d, 4> tet{c[0], c[1], c[2], view};
      for (const TileKey k : grid.tiles_crossed(tet)) roles[{k, {a, t}}] = TileRole::empty_space;
      for (const TileKey k : grid.halo_tiles(box, owner)) roles[{k, {a, t}}] = TileRole::halo;
      roles[{owner, {a, t}}] = TileRole::owned;
    }
  }
  return roles;
}

/// Checks every chunk of `store` against expected_roles(f).
void expect_brute_force_roles(const Fixture& f, const TileStore& store) {
  ASSERT_EQ(store.triangles, (std::vector<std::uint64_t>{3000, 3000}));
  auto expected = expected_roles(f);
  std::uint64_t owned = 0;
  for (const TileContents& tile : store.tiles) {
    const std::vector<TilePiece> pieces = read_tile(store, tile.key);
    for (std::uint32_t a = 0; a < pieces.size(); ++a) {
      const TilePiece& p = pieces[a];
      std::array<std::uint64_t, 3> per_role{};
      for (std::size_t t = 0; t < p.triangle_count(); ++t) {
        const std::uint32_t index = p.triangle_index[t];
        const auto it = expected.find({tile.key, {a, index}});
        ASSERT_NE(it, expected.end()) << tile.key.name() << " holds " << a << "/" << index;
        EXPECT_EQ(it->second, p.roles[t]);
        expected.erase(it);
        ++per_role[static_cast<std::size_t>(p.roles[t])];
        // Local floats plus the tile corner give the input position back.
        const auto want = world_corners(f.meshes[a], index);
        for (std::size_t k = 0; k < 3; ++k) {
          const Vec3d got = p.mesh.world_position(p.mesh.triangles[t][k]);
          EXPECT_LT(norm(got - want[k]), 1e-5);
          EXPECT_EQ(p.mesh.intensities[p.mesh.triangles[t][k]],
                    f.meshes[a].intensities[f.meshes[a].triangles[index][k]]);
        }
      }
      EXPECT_EQ(per_role, tile.triangles[a]);
      owned += per_role[0];
      // One block per tile and acquisition (large buffers) holding each vertex once: its
      // header counts only the distinct vertices its triangles use, so a vertex written twice
      // would show.
      if (p.triangle_count() == 0) {
        EXPECT_TRUE(tile.blocks[a].empty());
        continue;
      }
      std::set<std::uint32_t> used;
      for (const Triangle& tri : p.mesh.triangles) {
        for (const std::uint32_t v : tri) used.insert(p.vertex_ids[v]);
      }
      ASSERT_EQ(tile.blocks[a].size(), 1u);
      const BlockCounts counts = block_counts(acquisition_blocks_path(store.dir, a), tile.blocks[a][0]);
      EXPECT_EQ(counts.vertices, used.size());
      EXPECT_EQ(counts.triangles, p.triangle_count());
      EXPECT_EQ(counts.bytes, tile.blocks[a][0].bytes);
    }
  }
  EXPECT_EQ(owned, 6000u);
  // Whatever remains expected belongs to tiles that own nothing (not listed: no work there).
  for (const auto& [key, role] : expected) {
    const bool listed =
        std::any_of(store.tiles.begin(), store.tiles.end(), [&](const TileContents& t) { return t.key == key.first; });
    EXPECT_FALSE(listed) << key.first.name();
  }
  EXPECT_GT(store.stats.halo_copies, 0u);
  EXPECT_GT(store.stats.empty_space_copies, 0u);
}

TEST(Tiler, EveryTriangleIsOwnedOnceAndCopiedWhereBruteForceSays) {
  Fixture f;
  expect_brute_force_roles(f, tile_acquisitions(f.acquisitions, f.params));
}

TEST(Tiler, TrianglesInScanOrderAreOwnedAndCopiedWhereBruteForceSays) {
  // The tiler places a triangle within the last owner's interior without owner(): runs of
  // triangles in one tile, and every step from one tile to the next, must still be placed as
  // the grid says.
  Fixture f(256ull << 20, true);
  expect_brute_force_roles(f, tile_acquisitions(f.acquisitions, f.params));
}

TEST(Tiler, TheLargestRadiusIsTheBruteForceMaximumOverEveryTriangle) {
  Fixture f;
  double expected = 0;
  for (const Mesh& m : f.meshes) {
    for (std::size_t t = 0; t < m.triangle_count(); ++t) {
      const auto c = world_corners(m, t);
      const Vec3d centroid = (c[0] + c[1] + c[2]) / 3.0;
      for (const Vec3d& p : c) expected = std::max(expected, std::hypot(p.x - centroid.x, p.y - centroid.y));
    }
  }
  const TileStore store = tile_acquisitions(f.acquisitions, f.params);
  EXPECT_GT(expected, 0.5);
  EXPECT_NEAR(store.stats.largest_radius, expected, 1e-9);
  // It survives the manifest (and a store written before it existed reads as 0).
  TileStore written = store;
  written.fingerprint = "abc";
  write_tile_manifest(written);
  const std::optional<TileStore> back = read_tile_manifest(store.dir);
  ASSERT_TRUE(back.has_value());
  EXPECT_EQ(back->stats.largest_radius, store.stats.largest_radius);
}

TEST(Tiler, SmallBuffersWriteManyBlocksThatReadBackTheSame) {
  Fixture whole, blocks(64 << 10);
  const TileStore a = tile_acquisitions(whole.acquisitions, whole.params);
  const TileStore b = tile_acquisitions(blocks.acquisitions, blocks.params);
  EXPECT_GT(b.stats.blocks, 4 * a.stats.blocks);
  ASSERT_EQ(a.tiles.size(), b.tiles.size());
  for (std::size_t k = 0; k < a.tiles.size(); ++k) {
    const auto pa = read_tile(a, a.tiles[k].key), pb = read_tile(b, b.tiles[k].key);
    for (std::size_t q = 0; q < pa.size(); ++q) {
      // Same triangles in the same order with the same corners; shared vertices stay shared.
      ASSERT_EQ(pa[q].triangle_index, pb[q].triangle_index);
      ASSERT_EQ(pa[q].mesh.vertex_count(), pb[q].mesh.vertex_count());
      for (std::size_t t = 0; t < pa[q].triangle_count(); ++t) {
        for (std::size_t c = 0; c < 3; ++c) {
          ASSERT_EQ(pa[q].vertex_ids[pa[q].mesh.triangles[t][c]], pb[q].vertex_ids[pb[q].mesh.triangles[t][c]]);
        }
      }
    }
  }
}

TEST(Tiler, ManifestRoundTrips) {
  Fixture f;
  TileStore store = tile_acquisitions(f.acquisitions, f.params);
  EXPECT_FALSE(read_tile_manifest(store.dir).has_value());  // unfinished until the manifest is written
  store.fingerprint = "abc";
  write_tile_manifest(store);
  const std::optional<TileStore> back = read_tile_manifest(store.dir);
  ASSERT_TRUE(back.has_value());
  EXPECT_EQ(back->fingerprint, "abc");
  EXPECT_EQ(back->triangles, store.triangles);
  ASSERT_EQ(back->tiles.size(), store.tiles.size());
  for (std::size_t k = 0; k < store.tiles.size(); ++k) {
    EXPECT_EQ(back->tiles[k].key, store.tiles[k].key);
    EXPECT_EQ(back->tiles[k].triangles, store.tiles[k].triangles);
    EXPECT_EQ(back->tiles[k].blocks, store.tiles[k].blocks);
  }
}

TEST(Tiler, AManifestOfAnOlderLayoutIsNoFinishedStoreAndOneOfANewerIsAnError) {
  Fixture f;
  TileStore store = tile_acquisitions(f.acquisitions, f.params);
  write_tile_manifest(store);
  const auto manifest = store.dir / "manifest.json";
  const std::string text = test::read_text(manifest);
  const auto with_version = [&](int version) {
    std::string changed = text;
    const std::size_t at = changed.find("\"version\": 3");
    EXPECT_NE(at, std::string::npos);
    changed.replace(at, 12, "\"version\": " + std::to_string(version));
    test::write_text(manifest, changed);
  };
  with_version(1);  // a file per tile and acquisition: its acquisitions are tiled again
  EXPECT_FALSE(read_tile_manifest(store.dir).has_value());
  with_version(2);  // no checksum
  EXPECT_FALSE(read_tile_manifest(store.dir).has_value());
  with_version(4);  // a newer build's: not ours to replace
  EXPECT_THROW((void)read_tile_manifest(store.dir), InputError);
}

TEST(Tiler, ADamagedManifestIsNoFinishedStoreEvenWhenItStillParses) {
  Fixture f;
  TileStore store = tile_acquisitions(f.acquisitions, f.params);
  write_tile_manifest(store);
  ASSERT_TRUE(read_tile_manifest(store.dir).has_value());
  const auto manifest = store.dir / "manifest.json";
  const std::string text = test::read_text(manifest);
  // A digit of a block's offset changed: still valid JSON, but the blocks would be misread.
  const std::size_t blocks = text.find("\"blocks\"");
  ASSERT_NE(blocks, std::string::npos);
  std::size_t digit = text.find_first_of("123456789", blocks);
  ASSERT_NE(digit, std::string::npos);
  std::string changed = text;
  changed[digit] = changed[digit] == '9' ? '8' : static_cast<char>(changed[digit] + 1);
  test::write_text(manifest, changed);
  EXPECT_FALSE(read_tile_manifest(store.dir).has_value());
  test::write_text(manifest, text.substr(0, text.size() / 2));  // cut short: does not parse
  EXPECT_FALSE(read_tile_manifest(store.dir).has_value());
  test::write_text(manifest, text);
  EXPECT_TRUE(read_tile_manifest(store.dir).has_value());
}

TEST(Tiler, DamagedBlocksAreInputErrorsNamingTheFileAndTile) {
  Fixture f;
  TileStore store = tile_acquisitions(f.acquisitions, f.params);
  const TileContents& tile = store.tiles.front();
  const auto file = acquisition_blocks_path(store.dir, 0);
  ASSERT_FALSE(tile.blocks[0].empty());
  const ByteRange block = tile.blocks[0].front();
  const auto expect_error = [&](const std::string& what) {
    try {
      (void)read_tile(store, tile.key);
      FAIL() << "no error for " << what;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(file.string() + " (tile " + tile.key.name() + ")"), std::string::npos)
          << e.what();
    }
  };
  {
    std::fstream io(file, std::ios::in | std::ios::out | std::ios::binary);
    io.seekp(static_cast<std::streamoff>(block.offset + block.bytes / 2));
    io.put('\x7f');
  }
  expect_error("a flipped byte");
  std::filesystem::resize_file(file, block.offset + block.bytes - 7);
  expect_error("a truncated block");
  std::filesystem::resize_file(file, block.offset + 20);
  expect_error("a truncated header");
  // A damaged manifest naming a block far past the file's end: an error, not a huge allocation.
  store.tiles.front().blocks[0] = {{0, 1ull << 50}};
  expect_error("a block past the end");
}

/// Moves vertex `v` of acquisition 1 with its sensor position to vertex `from`'s position plus
/// `d` (face 1 is {0, 1, 3}, and vertex 3 is used by face 1 only).
void move_vertex(Fixture& f, std::uint32_t v, std::uint32_t from, const Vec3d& d) {
  Mesh& m = f.meshes[1];
  const Vec3f to = Vec3f(Vec3d(m.positions[from]) + d);
  m.sensor_positions[v] = m.sensor_positions[v] + (to - m.positions[v]);
  m.positions[v] = to;
  write_mesh_ply(f.acquisitions[1].path, m);
}

/// Moves vertex 3 (used by face 1 only) and its sensor position `dx` metres along x.
void stretch_face_one(Fixture& f, double dx) { move_vertex(f, 3, 3, {dx, 0, 0}); }

TEST(Tiler, AFaceLongerThanTheMaximumReachIsAnInputErrorNamingFileAndFace) {
  // Without this check one corrupt vertex had the change step fill voxels between Paris and
  // its copy 1000 km away: a run that never ended.
  Fixture f;
  stretch_face_one(f, 0.9 * kMaxReach);  // long, but not beyond belief: tiled as usual
  EXPECT_NO_THROW((void)tile_acquisitions(f.acquisitions, f.params));
  EXPECT_NO_THROW((void)read_mesh(f.acquisitions[1].path));
  stretch_face_one(f, 0.2 * kMaxReach);
  const auto expect_error = [&](const std::function<void()>& read) {
    try {
      read();
      FAIL() << "no error";
    } catch (const InputError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(f.acquisitions[1].path.string() + ": face 1: an edge of"), std::string::npos) << what;
    }
  };
  expect_error([&] { (void)tile_acquisitions(f.acquisitions, f.params); });
  expect_error([&] { (void)read_mesh(f.acquisitions[1].path); });
}

TEST(Tiler, AFaceWhoseBoxDiagonalPassesTheMaximumReachButNoEdgeDoesIsTiled) {
  // The tiler checks the box of a face's corners first and its edges only when the box's
  // diagonal passes the limit: a face 0.7 of the reach long along every axis (edges of 0.99,
  // diagonal 1.21 of it) must pass that second check.
  Fixture f;
  const double r = 0.7 * kMaxReach;
  move_vertex(f, 3, 1, {r, 0, r});
  move_vertex(f, 0, 1, {0, r, r});
  const TileStore store = tile_acquisitions(f.acquisitions, f.params);
  EXPECT_EQ(store.triangles[1], f.meshes[1].triangle_count());
  EXPECT_NO_THROW((void)read_mesh(f.acquisitions[1].path));
  // 30 m more along x take the edges from vertex 3 past the limit (about 1011 m).
  move_vertex(f, 3, 3, {30, 0, 0});
  EXPECT_THROW((void)tile_acquisitions(f.acquisitions, f.params), InputError);
}

TEST(Tiler, ZeroAreaTrianglesAreDroppedAndTheRestNumberedAsWholeMeshReadingNumbersThem) {
  // A tiled run reads each acquisition again for its labelled PLY; the tiler and whole-mesh
  // reading must drop the same triangles, or every label after a degenerate face is shifted
  // (the run used to stop there, "N triangles now, N + 1 labelled").
  Fixture f;
  move_vertex(f, 3, 1, {0, 0, 0});  // face 1 = {0, 1, 3} collapses onto its edge {0, 1}
  const MeshReadResult whole = read_mesh(f.acquisitions[1].path);
  ASSERT_EQ(whole.zero_area_dropped, 1u);
  const TileStore store = tile_acquisitions(f.acquisitions, f.params);
  ASSERT_EQ(store.triangles[1], whole.mesh.triangle_count());
  std::set<std::uint32_t> owned;
  for (const TileContents& tile : store.tiles) {
    const TilePiece p = read_tile(store, tile.key)[1];
    for (std::size_t t = 0; t < p.triangle_count(); ++t) {
      const std::uint32_t index = p.triangle_index[t];
      ASSERT_LT(index, whole.mesh.triangle_count());
      EXPECT_EQ(p.mesh.triangle_ids[t].face, whole.mesh.triangle_ids[index].face) << "triangle " << index;
      EXPECT_NE(p.mesh.triangle_ids[t].face, 1u);
      if (p.roles[t] == TileRole::owned) {
        EXPECT_TRUE(owned.insert(index).second) << "owned twice: " << index;
      }
    }
  }
  EXPECT_EQ(owned.size(), whole.mesh.triangle_count());
}

/// Every file under `dir` by relative path, with its bytes.
std::map<std::string, std::string> folder_bytes(const std::filesystem::path& dir) {
  std::map<std::string, std::string> files;
  for (const auto& e : std::filesystem::recursive_directory_iterator(dir)) {
    if (!e.is_regular_file()) continue;
    std::ifstream in(e.path(), std::ios::binary);
    files[std::filesystem::relative(e.path(), dir).string()] =
        std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  }
  return files;
}

TEST(Tiler, AcquisitionsTiledSeparatelyOrTwiceGiveTheSameStore) {
  Fixture f;
  const TileStore whole = tile_acquisitions(f.acquisitions, f.params);
  const auto reference = folder_bytes(f.params.dir);
  // As the ranks of a cluster do: acquisitions in another order, one of them twice (two
  // processes racing: the second finds the first's copy and keeps it), then assembled.
  std::filesystem::remove_all(f.params.dir);
  const AcquisitionTiling b = tile_acquisition(f.acquisitions[1], f.params, "fp");
  const AcquisitionTiling a = tile_acquisition(f.acquisitions[0], f.params, "fp");
  const AcquisitionTiling again = tile_acquisition(f.acquisitions[0], f.params, "fp");
  EXPECT_EQ(again.tiles, a.tiles);
  EXPECT_TRUE(std::filesystem::is_empty(f.params.dir / "staging")) << "a losing copy was left behind";
  const std::vector<AcquisitionTiling> parts{*read_acquisition_tiling(f.params.dir, 0, "fp"),
                                             *read_acquisition_tiling(f.params.dir, 1, "fp")};
  const TileStore assembled = assemble_tile_store(f.params.dir, f.params.grid, parts, "fp");
  EXPECT_EQ(assembled.triangles, whole.triangles);
  ASSERT_EQ(assembled.tiles.size(), whole.tiles.size());
  for (std::size_t k = 0; k < whole.tiles.size(); ++k) {
    EXPECT_EQ(assembled.tiles[k].key, whole.tiles[k].key);
    EXPECT_EQ(assembled.tiles[k].triangles, whole.tiles[k].triangles);
  }
  auto files = folder_bytes(f.params.dir);
  auto expected = reference;
  for (auto* m : {&files, &expected})
    std::erase_if(*m, [](const auto& e) { return e.first.ends_with("summary.json"); });
  EXPECT_TRUE(files == expected) << "block files differ from a store tiled in one go";
  for (std::size_t k = 0; k < whole.tiles.size(); ++k) EXPECT_EQ(assembled.tiles[k].blocks, whole.tiles[k].blocks);
  EXPECT_EQ(b.triangles, 3000u);
}

TEST(Tiler, TwoAcquisitionsAtOnceGiveTheSameBlockBytes) {
  // Small buffers: many flushes, so vertex cache slots move between buffers on the way.
  Fixture f(64 << 10);
  const TileStore store_one = tile_acquisitions(f.acquisitions, f.params, 1);
  auto one = folder_bytes(f.params.dir);
  const ThreadLimit limit(2);
  const TileStore store_two = tile_acquisitions(f.acquisitions, f.params, 2);
  auto two = folder_bytes(f.params.dir);
  ASSERT_EQ(store_one.tiles.size(), store_two.tiles.size());
  for (std::size_t k = 0; k < store_one.tiles.size(); ++k)
    EXPECT_EQ(store_one.tiles[k].blocks, store_two.tiles[k].blocks);
  // The summaries hold the tiling time; everything else must match byte for byte.
  for (auto* m : {&one, &two}) std::erase_if(*m, [](const auto& e) { return e.first.ends_with("summary.json"); });
  EXPECT_EQ(one.size(), 2u);
  EXPECT_TRUE(one == two) << "block files differ between one and two acquisitions at once";
}

TEST(Tiler, PruneKeepsEachAcquisitionTiledWithItsOwnFingerprint) {
  Fixture f;
  std::filesystem::remove_all(f.params.dir);
  (void)tile_acquisition(f.acquisitions[0], f.params, "a0");
  (void)tile_acquisition(f.acquisitions[1], f.params, "a1 before");
  std::filesystem::create_directories(f.params.dir / "3_4");             // an older layout
  std::filesystem::create_directories(f.params.dir / "a7");              // beyond the acquisitions
  std::filesystem::create_directories(f.params.dir / "staging/a0.x.1");  // another process's work
  const std::vector<std::string> fingerprints{"a0", "a1 now"};
  prune_tile_store(f.params.dir, fingerprints, "store", false);
  EXPECT_TRUE(read_acquisition_tiling(f.params.dir, 0, "a0").has_value()) << "its own fingerprint: kept";
  EXPECT_FALSE(std::filesystem::exists(f.params.dir / "a1"));
  EXPECT_FALSE(std::filesystem::exists(f.params.dir / "3_4"));
  EXPECT_FALSE(std::filesystem::exists(f.params.dir / "a7"));
  EXPECT_TRUE(std::filesystem::exists(f.params.dir / "staging/a0.x.1")) << "staging kept when others may tile";
  prune_tile_store(f.params.dir, fingerprints, "store", true);
  EXPECT_FALSE(std::filesystem::exists(f.params.dir / "staging"));
  EXPECT_FALSE(read_acquisition_tiling(f.params.dir, 0, "other").has_value());
}

TEST(Tiler, RenumberedAcquisitionsTilingsAreMovedToTheirNewIndexNotMadeAgain) {
  Fixture f;
  std::filesystem::remove_all(f.params.dir);
  const AcquisitionTiling p = tile_acquisition(f.acquisitions[0], f.params, "p");
  const AcquisitionTiling q = tile_acquisition(f.acquisitions[1], f.params, "q");
  const auto blocks = [&](std::uint32_t k) { return test::read_text(acquisition_blocks_path(f.params.dir, k)); };
  const std::string q_blocks = blocks(1);
  const auto expect_at = [&](std::uint32_t k, const char* fingerprint, const AcquisitionTiling& tiling) {
    const std::optional<AcquisitionTiling> found = read_acquisition_tiling(f.params.dir, k, fingerprint);
    ASSERT_TRUE(found.has_value()) << fingerprint << " at " << k;
    EXPECT_EQ(found->tiles, tiling.tiles);
  };
  // A pass delivered late, older than q: q becomes acquisition 2, the late pass 1 (not tiled).
  EXPECT_EQ(move_renumbered_tilings(f.params.dir, std::vector<std::string>{"p", "late", "q"}), 1u);
  expect_at(0, "p", p);
  expect_at(2, "q", q);
  EXPECT_EQ(blocks(2), q_blocks);
  EXPECT_FALSE(std::filesystem::exists(acquisition_tiles_path(f.params.dir, 1)));
  EXPECT_EQ(move_renumbered_tilings(f.params.dir, std::vector<std::string>{"p", "late", "q"}), 0u) << "in place";
  // A fingerprint listed twice (no config does) takes no folder from its own place, nor one twice.
  EXPECT_EQ(move_renumbered_tilings(f.params.dir, std::vector<std::string>{"p", "q", "q", "p", "q"}), 0u);
  expect_at(2, "q", q);
  // Removed again: q moves back down.
  EXPECT_EQ(move_renumbered_tilings(f.params.dir, std::vector<std::string>{"p", "q"}), 1u);
  expect_at(1, "q", q);
  EXPECT_FALSE(std::filesystem::exists(acquisition_tiles_path(f.params.dir, 2)));
  // Two passes re-dated past each other swap folders (each folder the source of one move and
  // the target of the other); a folder of a fingerprint no acquisition has stays for pruning.
  std::filesystem::create_directories(f.params.dir / "a5");
  EXPECT_EQ(move_renumbered_tilings(f.params.dir, std::vector<std::string>{"q", "p"}), 2u);
  expect_at(0, "q", q);
  expect_at(1, "p", p);
  EXPECT_EQ(blocks(0), q_blocks);
  EXPECT_TRUE(std::filesystem::exists(f.params.dir / "a5"));
  prune_tile_store(f.params.dir, std::vector<std::string>{"q", "p"}, "store", true);
  EXPECT_FALSE(std::filesystem::exists(f.params.dir / "staging")) << "nothing left aside";
  expect_at(0, "q", q);
}

TEST(Tiler, ADamagedAcquisitionSummaryIsNotReusedEvenWhenItStillParses) {
  Fixture f;
  std::filesystem::remove_all(f.params.dir);
  (void)tile_acquisition(f.acquisitions[0], f.params, "a0");
  ASSERT_TRUE(read_acquisition_tiling(f.params.dir, 0, "a0").has_value());
  const auto summary = acquisition_tiles_path(f.params.dir, 0) / "summary.json";
  const std::string text = test::read_text(summary);
  const std::size_t blocks = text.find("\"blocks\"");
  ASSERT_NE(blocks, std::string::npos);
  const std::size_t digit = text.find_first_of("123456789", blocks);
  ASSERT_NE(digit, std::string::npos);
  std::string changed = text;
  changed[digit] = changed[digit] == '9' ? '8' : static_cast<char>(changed[digit] + 1);
  test::write_text(summary, changed);
  EXPECT_FALSE(read_acquisition_tiling(f.params.dir, 0, "a0").has_value()) << "a block's range changed";
  test::write_text(summary, text);
  EXPECT_TRUE(read_acquisition_tiling(f.params.dir, 0, "a0").has_value());
}

}  // namespace
}  // namespace citymesh
