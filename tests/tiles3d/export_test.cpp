// SPDX-License-Identifier: MIT
// 3D Tiles export against ground truth: every triangle in the leaves, borders bit-identical,
// the globe placement against PROJ, external tilesets, determinism, and `check` failures.
// Reference ECEF position computed with PROJ 9.1.1 (Debian proj-bin):
//   echo "651070 6860700 50" | cs2cs -f %.6f EPSG:2154 EPSG:4978
//   -> 4202017.855690 171215.722181 4779232.622308
#include "citymesh/tiles3d/export.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <functional>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <set>

#include "citymesh/core/error.h"
#include "citymesh/core/parallel.h"
#include "citymesh/encode/glb.h"
#include "citymesh/tiles3d/check.h"
#include "grid_triangles.h"
#include "test_support.h"

namespace citymesh {
namespace {

constexpr Vec3d kKnownPoint{651070, 6860700, 50};
constexpr Vec3d kKnownEcef{4202017.855690, 171215.722181, 4779232.622308};
constexpr int kSide = 120;  // metres, one vertex per metre

/// A gently wavy 120 m square in Lambert-93 whose vertex (70, 100) is kKnownPoint; three
/// source acquisitions in bands of columns, and one row of stitch triangles.
struct Scene {
  Mesh mesh;
  std::vector<std::int32_t> source;
};

Scene scene() {
  Scene s;
  s.mesh.origin = {651000, 6860600, 50};
  for (int i = 0; i <= kSide; ++i) {
    for (int j = 0; j <= kSide; ++j) {
      const double z = 0.2 * std::sin(0.3 * (i - 70)) * std::sin(0.2 * j);
      s.mesh.positions.push_back({float(i), float(j), float(z)});
    }
  }
  s.mesh.triangles = test::grid_triangles(kSide);
  for (int i = 0; i < kSide; ++i) {
    for (int j = 0; j < kSide; ++j) {
      const std::int32_t source = j == 60 ? -1 : i / 40;
      s.source.insert(s.source.end(), {source, source});  // the cell's two triangles
    }
  }
  s.mesh.triangle_ids.resize(s.mesh.triangles.size());
  return s;
}

const Crs& lambert93() {
  static const Crs crs = Crs::parse("EPSG:2154", {VerticalDatum::Kind::ellipsoidal, 0.0});
  return crs;
}

TilesetExportParams params(const std::filesystem::path& dir) {
  TilesetExportParams p;
  p.dir = dir;
  p.grid = {.tile_size = 25.0, .halo = 1.0, .origin = {0.0, 0.0}};
  p.acquisitions = {{"a", "2026-01-01T00:00:00Z"}, {"b", "2026-02-01T00:00:00Z"}, {"c", "2026-03-01T00:00:00Z"}};
  return p;
}

nlohmann::json read_json(const std::filesystem::path& path) { return nlohmann::json::parse(test::read_text(path)); }

DecodedMesh decode(const std::filesystem::path& path) {
  const std::string bytes = test::read_text(path);
  const std::vector<std::uint8_t> data(bytes.begin(), bytes.end());
  return read_glb_mesh(parse_glb(data, path.string()), path.string());
}

TEST(TilesetExport, EveryTriangleIsInExactlyOneLeafAndTheTilesetChecksOut) {
  test::TempDir tmp;
  const Scene s = scene();
  const TilesetExportStats stats = export_tileset({s.mesh, s.source, lambert93()}, params(tmp / "tiles"));
  EXPECT_EQ(stats.leaves, 25u);  // 120 m from a multiple of 25 m: 5 x 5 grid tiles
  EXPECT_EQ(stats.leaf_triangles, s.mesh.triangle_count());
  EXPECT_GE(stats.levels, 4u);
  EXPECT_LE(stats.quantization_step / 2, 0.001);
  const TilesetCheckReport r = check_tileset(tmp / "tiles");
  for (const std::string& e : r.errors) ADD_FAILURE() << e;
  EXPECT_EQ(r.leaf_triangles, s.mesh.triangle_count());
  EXPECT_EQ(r.tiles, stats.tiles);
  EXPECT_EQ(r.glb_files, stats.tiles);
  const nlohmann::json tileset = read_json(tmp / "tiles" / "tileset.json");
  EXPECT_EQ(tileset["asset"]["version"], "1.1");
  EXPECT_EQ(tileset["root"]["refine"], "REPLACE");
  EXPECT_GT(tileset["root"]["geometricError"].get<double>(), 0.0);
  // Parents are simplified: the root holds far fewer triangles than the leaves together.
  EXPECT_LT(stats.all_triangles, 2 * stats.leaf_triangles);
  // Simplified with their borders locked, parents meet their neighbours without cracks
  // along the 25 m grid's inner lines (4 + 4 lines of 120 m).
  EXPECT_NEAR(r.seam_length, 8 * 120.0, 1.0);
  EXPECT_EQ(r.crack_length, 0.0);
  EXPECT_TRUE(r.cracked_tiles.empty());
}

TEST(TilesetExport, ParentsPastTheCapKeepTheirSeamsWithTheirNeighbours) {
  test::TempDir tmp;
  const Scene s = scene();
  TilesetExportParams p = params(tmp / "tiles");
  // Below what four leaves with locked borders simplify to: simplified again with only the
  // seams with the neighbouring tiles locked.
  p.tree.max_parent_triangles = 300;
  (void)export_tileset({s.mesh, s.source, lambert93()}, p);
  const TilesetCheckReport r = check_tileset(tmp / "tiles");
  for (const std::string& e : r.errors) ADD_FAILURE() << e;
  EXPECT_NEAR(r.seam_length, 8 * 120.0, 1.0);
  EXPECT_EQ(r.crack_length, 0.0);
  std::size_t parents = 0;
  for (const auto& entry : std::filesystem::directory_iterator(tmp / "tiles")) {
    const std::string name = entry.path().filename().string();
    if (!name.ends_with(".glb") || name.starts_with("t0_")) continue;
    ++parents;
    EXPECT_LE(decode(entry.path()).triangles.size(), 300u) << name;
  }
  EXPECT_GE(parents, 5u);  // 25 leaves: 9 parents on level 1 (some carried), then 4 and 1
}

TEST(TilesetExport, AGridOriginInsideTheOutputGivesATreeAndAValidTileset) {
  // Keys of both signs on both axes (-3..2 by -3..2): halving never joins -1 and 0, so the tree
  // counts such an axis from its smallest key. This export used to loop forever.
  test::TempDir tmp;
  const Scene s = scene();
  TilesetExportParams p = params(tmp / "tiles");
  p.grid.origin = {651060.0, 6860660.0};
  const TilesetExportStats stats = export_tileset({s.mesh, s.source, lambert93()}, p);
  EXPECT_EQ(stats.leaves, 36u);  // 6 x 6 grid tiles: the square straddles theirs
  EXPECT_EQ(stats.leaf_triangles, s.mesh.triangle_count());
  const TilesetCheckReport r = check_tileset(tmp / "tiles");
  for (const std::string& e : r.errors) ADD_FAILURE() << e;
  EXPECT_EQ(r.leaf_triangles, s.mesh.triangle_count());
  EXPECT_EQ(r.glb_files, stats.tiles);
}

TEST(TilesetExport, NeighbouringLeavesDecodeSharedVerticesBitIdentically) {
  test::TempDir tmp;
  const Scene s = scene();
  export_tileset({s.mesh, s.source, lambert93()}, params(tmp / "tiles"));
  // Leaves t0_26040_274424 (x 651000..651025) and t0_26041_274424 (651025..651050) meet at
  // x = 651025: every vertex on that line used by both must decode to the same floats.
  const DecodedMesh a = decode(tmp / "tiles" / "t0_26040_274424.glb");
  const DecodedMesh b = decode(tmp / "tiles" / "t0_26041_274424.glb");
  auto key = [](const Vec3f& p) { return std::array<float, 3>{p.x, p.y, p.z}; };
  std::set<std::array<float, 3>> in_b;
  for (const Vec3f& p : b.positions) in_b.insert(key(p));
  std::set<std::array<float, 3>> shared;
  for (const Vec3f& p : a.positions) {
    if (in_b.count(key(p))) shared.insert(key(p));
  }
  // Column x = 25 (and, through triangles whose centroid falls in either tile, x = 24 or
  // 26 in places): at least the 26 vertices of the border column, rows 0..25.
  EXPECT_GE(shared.size(), 26u);
}

TEST(TilesetExport, EveryLeafTriangleCarriesItsSourceAsOneFeatureId) {
  // Vertices on the band borders (columns 40 and 80) belong to two sources, and those where a
  // border meets the stitch row (j = 60) to three: each source's triangles need their own copy.
  test::TempDir tmp;
  const Scene s = scene();
  export_tileset({s.mesh, s.source, lambert93()}, params(tmp / "tiles"));
  std::map<std::uint16_t, std::size_t> expected, found;
  for (const std::int32_t source : s.source) {
    ++expected[source < 0 ? kNullFeatureId : static_cast<std::uint16_t>(source)];
  }
  for (const auto& entry : std::filesystem::directory_iterator(tmp / "tiles")) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("t0_", 0) != 0 || entry.path().extension() != ".glb") continue;
    const DecodedMesh m = decode(entry.path());
    ASSERT_EQ(m.feature_ids.size(), m.positions.size()) << name;
    for (const Triangle& t : m.triangles) {
      const std::uint16_t f = m.feature_ids[t[0]];
      EXPECT_EQ(m.feature_ids[t[1]], f) << name;
      EXPECT_EQ(m.feature_ids[t[2]], f) << name;
      ++found[f];
    }
  }
  EXPECT_EQ(found, expected);
}

TEST(TilesetExport, RootTransformPutsAKnownPointWhereProjDoes) {
  test::TempDir tmp;
  const Scene s = scene();
  export_tileset({s.mesh, s.source, lambert93()}, params(tmp / "tiles"));
  const nlohmann::json tileset = read_json(tmp / "tiles" / "tileset.json");
  const std::vector<double> m = tileset["root"]["transform"].get<std::vector<double>>();
  ASSERT_EQ(m.size(), 16u);
  // kKnownPoint is vertex (70, 100): tile (651070 / 25, 6860700 / 25) = (26042, 274428), or
  // its neighbour below when the triangles around it have their centroids there.
  double best = 1e9;
  for (const char* name :
       {"t0_26042_274428.glb", "t0_26042_274427.glb", "t0_26041_274428.glb", "t0_26041_274427.glb"}) {
    const DecodedMesh d = decode(tmp / "tiles" / name);
    for (const Vec3f& p : d.positions) {
      const Vec3d l(p);
      const Vec3d ecef{m[0] * l.x + m[4] * l.y + m[8] * l.z + m[12], m[1] * l.x + m[5] * l.y + m[9] * l.z + m[13],
                       m[2] * l.x + m[6] * l.y + m[10] * l.z + m[14]};
      best = std::min(best, norm(ecef - kKnownEcef));
    }
  }
  EXPECT_LT(best, 0.01);  // vertices are 1 m apart: only the known point can be this close
}

std::map<std::string, std::string> folder_bytes(const std::filesystem::path& dir) {
  std::map<std::string, std::string> out;
  for (const auto& e : std::filesystem::directory_iterator(dir))
    out[e.path().filename().string()] = test::read_text(e.path());
  return out;
}

/// Every file of the two folders, byte for byte.
void expect_same_files(const std::filesystem::path& a, const std::filesystem::path& b) {
  const auto x = folder_bytes(a), y = folder_bytes(b);
  EXPECT_EQ(x.size(), y.size());
  EXPECT_TRUE(x == y) << a << " and " << b << " differ";
}

TEST(TilesetExport, LargeTreesAreSplitIntoExternalTilesets) {
  test::TempDir tmp;
  const Scene s = scene();
  TilesetExportParams p = params(tmp / "tiles");
  p.max_tiles_per_file = 5;
  const TilesetExportStats stats = export_tileset({s.mesh, s.source, lambert93()}, p);
  EXPECT_GT(stats.json_files, 1u);
  const TilesetCheckReport r = check_tileset(tmp / "tiles");
  for (const std::string& e : r.errors) ADD_FAILURE() << e;
  EXPECT_EQ(r.json_files, stats.json_files);
  EXPECT_EQ(r.leaf_triangles, s.mesh.triangle_count());
  for (const auto& [name, text] : folder_bytes(tmp / "tiles")) {
    if (!name.ends_with(".json")) continue;
    const nlohmann::json j = nlohmann::json::parse(text);
    std::size_t tiles = 0;
    std::function<void(const nlohmann::json&)> count = [&](const nlohmann::json& t) {
      ++tiles;
      for (const auto& c : t.value("children", nlohmann::json::array())) count(c);
    };
    count(j["root"]);
    EXPECT_LE(tiles, 5u) << name;
  }
}

TEST(TilesetExport, SameBytesOnOneAndTwoThreads) {
  test::TempDir tmp;
  const Scene s = scene();
  {
    const ThreadLimit one(1);
    export_tileset({s.mesh, s.source, lambert93()}, params(tmp / "one"));
  }
  {
    const ThreadLimit two(2);
    export_tileset({s.mesh, s.source, lambert93()}, params(tmp / "two"));
  }
  expect_same_files(tmp / "one", tmp / "two");
}

/// The scene given a leaf at a time, each leaf's triangles keyed by the scene's vertex indices.
class SceneLeaves final : public TilesetLeaves {
 public:
  SceneLeaves(const Scene& s, const TileGridParams& grid) : scene_(s) {
    const std::vector<TileKey> keys = leaf_keys(s.mesh, TileGrid(grid));
    for (std::uint32_t t = 0; t < keys.size(); ++t) by_leaf_[keys[t]].push_back(t);
  }
  [[nodiscard]] std::vector<TileKey> keys() const override {
    std::vector<TileKey> out;
    for (const auto& [key, ts] : by_leaf_) out.push_back(key);
    return out;
  }
  [[nodiscard]] Box3d box() const override {
    Box3d b;
    for (std::size_t v = 0; v < scene_.mesh.vertex_count(); ++v) b.extend(scene_.mesh.world_position(v));
    return b;
  }
  [[nodiscard]] TileMesh leaf(const TileKey& key, const LocalMapping& to_local) const override {
    KeyedPiece p;
    const std::vector<std::uint32_t>& ts = by_leaf_.at(key);
    for (const std::uint32_t t : ts)
      p.keys.insert(p.keys.end(), scene_.mesh.triangles[t].begin(), scene_.mesh.triangles[t].end());
    std::sort(p.keys.begin(), p.keys.end());
    p.keys.erase(std::unique(p.keys.begin(), p.keys.end()), p.keys.end());
    for (const std::uint64_t v : p.keys) p.positions.push_back(scene_.mesh.world_position(static_cast<std::size_t>(v)));
    for (const std::uint32_t t : ts) {
      Triangle tri{};
      for (std::size_t k = 0; k < 3; ++k) {
        tri[k] = static_cast<std::uint32_t>(
            std::lower_bound(p.keys.begin(), p.keys.end(), scene_.mesh.triangles[t][k]) - p.keys.begin());
      }
      p.triangles.push_back(tri);
      p.ids.push_back({});
      p.source_acq.push_back(scene_.source[t]);
      p.source_triangle.push_back(static_cast<std::int32_t>(t));
    }
    return tile_mesh(p, to_local);
  }

 private:
  const Scene& scene_;
  std::map<TileKey, std::vector<std::uint32_t>> by_leaf_;
};

TEST(TilesetExport, ALeafAtATimeGivesTheBytesOfTheWholeMesh) {
  // The scene's positions are exact in floats and doubles alike, so both ways see the same
  // vertices: every file must be the same, stitch triangles' vertices split by feature too.
  test::TempDir tmp;
  const Scene s = scene();
  const TilesetExportStats whole = export_tileset({s.mesh, s.source, lambert93()}, params(tmp / "whole"));
  const TilesetExportStats leaves =
      export_tileset(SceneLeaves(s, params(tmp.path()).grid), lambert93(), params(tmp / "leaves"));
  EXPECT_EQ(leaves.tiles, whole.tiles);
  EXPECT_EQ(leaves.all_triangles, whole.all_triangles);
  expect_same_files(tmp / "whole", tmp / "leaves");
}

/// A cache (GlbPrimitiveCache, SimplifyCache) in memory, counting what was found and kept.
template <class Cache, class Value>
class Counting final : public Cache {
 public:
  [[nodiscard]] std::optional<Value> find(std::uint64_t digest) const override {
    const std::lock_guard lock(mutex_);
    const auto it = kept_.find(digest);
    if (it == kept_.end()) return std::nullopt;
    ++found;
    return it->second;
  }
  void keep(std::uint64_t digest, const Value& value) override {
    const std::lock_guard lock(mutex_);
    kept_[digest] = value;
    ++made;
  }
  mutable std::size_t found = 0;
  std::size_t made = 0;

 private:
  mutable std::mutex mutex_;
  std::map<std::uint64_t, Value> kept_;
};
using CountingPrimitives = Counting<GlbPrimitiveCache, GlbPrimitive>;
using CountingSimplified = Counting<SimplifyCache, SimplifiedMesh>;

TEST(TilesetExport, KeptPrimitivesGiveTheBytesOfEncodingAndOnlyChangedTilesAreEncodedAgain) {
  test::TempDir tmp;
  Scene s = scene();
  CountingPrimitives cache;
  TilesetExportParams with = params(tmp / "first");
  with.primitives = &cache;
  const TilesetExportStats first = export_tileset({s.mesh, s.source, lambert93()}, with);
  (void)export_tileset({s.mesh, s.source, lambert93()}, params(tmp / "plain"));
  expect_same_files(tmp / "first", tmp / "plain");
  EXPECT_EQ(cache.made, first.tiles);
  EXPECT_EQ(cache.found, 0u);

  with.dir = tmp / "again";
  (void)export_tileset({s.mesh, s.source, lambert93()}, with);
  expect_same_files(tmp / "again", tmp / "plain");
  EXPECT_EQ(cache.found, first.tiles) << "every tile found";

  // One corner cell of the grid moves: its leaf and the parents above it change, the other
  // leaves are found. The acquisition list grows too, as when one is appended: the
  // primitives do not hold it.
  s.mesh.positions[0].z += 0.5f;
  const std::size_t found_before = cache.found, made_before = cache.made;
  with.dir = tmp / "changed";
  with.acquisitions.push_back({"d", "2026-04-01T00:00:00Z"});
  TilesetExportParams plain = params(tmp / "changed-plain");
  plain.acquisitions = with.acquisitions;
  const TilesetExportStats changed = export_tileset({s.mesh, s.source, lambert93()}, with);
  (void)export_tileset({s.mesh, s.source, lambert93()}, plain);
  expect_same_files(tmp / "changed", tmp / "changed-plain");
  const std::size_t made = cache.made - made_before, found = cache.found - found_before;
  EXPECT_EQ(made + found, changed.tiles);
  EXPECT_GE(made, 2u) << "the leaf and its parents";
  EXPECT_GE(found, changed.leaves - 1) << "the other leaves";
}

TEST(TilesetExport, TheTilesetVersionChangesExactlyWhenATileDoes) {
  // asset.tilesetVersion: viewers that honour it add it to their requests, so an updated
  // map is fetched again instead of shown from their caches; an unchanged one is not.
  test::TempDir tmp;
  Scene s = scene();
  const auto version = [&](const std::string& name) {
    (void)export_tileset({s.mesh, s.source, lambert93()}, params(tmp / name));
    return read_json(tmp / name / "tileset.json")["asset"].value("tilesetVersion", std::string());
  };
  const std::string first = version("first");
  EXPECT_EQ(first.size(), 16u);
  EXPECT_EQ(version("again"), first);
  s.mesh.positions[0].z += 0.5f;  // one corner leaf (and its parents) change
  EXPECT_NE(version("moved"), first);
}

TEST(TilesetExport, KeptSimplificationsGiveTheSameTilesAndOnlyParentsOfChangedLeavesAreSimplifiedAgain) {
  test::TempDir tmp;
  Scene s = scene();
  const SceneLeaves plain_leaves(s, params(tmp.path()).grid);
  CountingSimplified cache;
  TilesetExportParams with = params(tmp / "first");
  with.tree.simplified = &cache;
  const TilesetExportStats first = export_tileset(plain_leaves, lambert93(), with);
  (void)export_tileset(plain_leaves, lambert93(), params(tmp / "plain"));
  expect_same_files(tmp / "first", tmp / "plain");
  const std::size_t parents = first.tiles - first.leaves;
  ASSERT_GE(parents, 3u);
  EXPECT_GE(cache.made, parents) << "every parent simplified once at least";
  EXPECT_EQ(cache.found, 0u);
  const std::size_t simplifications = cache.made;

  with.dir = tmp / "again";
  (void)export_tileset(plain_leaves, lambert93(), with);
  expect_same_files(tmp / "again", tmp / "plain");
  EXPECT_EQ(cache.found, simplifications) << "every simplification found";
  EXPECT_EQ(cache.made, simplifications);

  // A bump inside the first leaf (vertex (10, 10)): the parents above it are simplified
  // again, the others found, and the tiles are those of simplifying everything.
  s.mesh.positions[10 * (kSide + 1) + 10].z += 0.5f;
  const SceneLeaves bumped(s, params(tmp.path()).grid);
  const std::size_t found_before = cache.found, made_before = cache.made;
  with.dir = tmp / "bumped";
  (void)export_tileset(bumped, lambert93(), with);
  (void)export_tileset(bumped, lambert93(), params(tmp / "bumped-plain"));
  expect_same_files(tmp / "bumped", tmp / "bumped-plain");
  const std::size_t made = cache.made - made_before, found = cache.found - found_before;
  EXPECT_EQ(made + found, simplifications);
  EXPECT_GE(made, 1u) << "the parents above the bump";
  EXPECT_GE(found, 1u) << "the parents away from it";
}

TEST(TilesetExport, LeavesMappedAndCellsBuiltByOtherProcessesGiveTheBytesOfOneProcess) {
  // As an MPI job's ranks do: each leaf mapped and each cell built from a source and a frame
  // of its own, last first; the exporting process builds only the levels above the cells.
  test::TempDir tmp;
  const Scene s = scene();
  const SceneLeaves leaves(s, params(tmp.path()).grid);
  const TilesetExportStats here = export_tileset(leaves, lambert93(), params(tmp / "here"));
  const SceneLeaves other(s, params(tmp.path()).grid);
  std::size_t mapped = 0, cells = 0;
  ExportWork elsewhere;
  elsewhere.boxes = [&](const Geodetic& origin, std::span<const TileKey> keys,
                        const std::function<Box3d(std::size_t)>& /*here*/) {
    std::vector<Box3d> out(keys.size());
    for (std::size_t k = out.size(); k-- > 0;) out[k] = export_leaf_box(other, lambert93(), origin, keys[k]);
    mapped = out.size();
    return out;
  };
  elsewhere.cells = [&](const TilesetFrame& frame, const TileTreeBuild& tree,
                        const std::function<ExportedCell(std::size_t)>& /*here*/) {
    const TilesetFrame copied = frame;
    std::vector<ExportedCell> out(tree.cell_count());
    for (std::size_t c = out.size(); c-- > 0;) {
      out[c] = export_cell(other, lambert93(), copied, params(tmp / "apart"), c);
    }
    cells = out.size();
    return out;
  };
  const TilesetExportStats apart = export_tileset(leaves, lambert93(), params(tmp / "apart"), elsewhere);
  EXPECT_EQ(mapped, here.leaves);
  EXPECT_GE(cells, 4u);
  EXPECT_EQ(apart.tiles, here.tiles);
  EXPECT_EQ(apart.glb_bytes, here.glb_bytes);
  expect_same_files(tmp / "here", tmp / "apart");
}

TEST(TilesetExport, AnyDepthFirstSplitGivesTheSameFiles) {
  // The cells a cluster shares: how many there are changes which process builds what and the
  // order of the tree's nodes, never a file.
  test::TempDir tmp;
  const Scene s = scene();
  const SceneLeaves leaves(s, params(tmp.path()).grid);
  std::map<std::string, std::string> reference;
  for (const std::size_t cells : {std::size_t{16}, std::size_t{1}, std::size_t{4}, std::size_t{64}, SIZE_MAX}) {
    TilesetExportParams p = params(tmp / fmt::format("cells-{}", cells));
    p.tree.depth_first_cells = cells;
    p.max_tiles_per_file = 5;  // external tilesets too
    export_tileset(leaves, lambert93(), p);
    const auto bytes = folder_bytes(p.dir);
    if (reference.empty()) {
      reference = bytes;
      const auto json_files =
          std::count_if(bytes.begin(), bytes.end(), [](const auto& f) { return f.first.ends_with(".json"); });
      EXPECT_GT(json_files, 1) << "no external tileset";
    }
    EXPECT_EQ(bytes.size(), reference.size()) << cells << " cells";
    EXPECT_TRUE(bytes == reference) << cells << " cells";
  }
}

TEST(TilesetExport, ReExportReplacesTheWholeFolder) {
  test::TempDir tmp;
  const Scene s = scene();
  test::write_text(tmp / "tiles" / "stale.glb", "old");
  export_tileset({s.mesh, s.source, lambert93()}, params(tmp / "tiles"));
  EXPECT_FALSE(std::filesystem::exists(tmp / "tiles" / "stale.glb"));
  EXPECT_FALSE(std::filesystem::exists(tmp / "tiles.partial"));
  EXPECT_TRUE(std::filesystem::exists(tmp / "tiles" / "tileset.json"));
}

TEST(TilesetExport, ToleranceTooFineForTheExtentIsAConfigError) {
  test::TempDir tmp;
  const Scene s = scene();
  TilesetExportParams p = params(tmp / "tiles");
  p.tolerance = 1e-8;
  EXPECT_THROW(export_tileset({s.mesh, s.source, lambert93()}, p), ConfigError);
}

bool any_error_mentions(const TilesetCheckReport& r, const std::string& text) {
  for (const std::string& e : r.errors)
    if (e.find(text) != std::string::npos) return true;
  return false;
}

TEST(TilesetCheck, FindsTruncatedMissingAndInconsistentContent) {
  test::TempDir tmp;
  const Scene s = scene();
  export_tileset({s.mesh, s.source, lambert93()}, params(tmp / "tiles"));
  const std::filesystem::path dir = tmp / "tiles";
  const std::string glb = test::read_text(dir / "t0_26040_274424.glb");
  test::write_text(dir / "t0_26040_274424.glb", glb.substr(0, glb.size() / 2));
  std::filesystem::remove(dir / "t0_26044_274428.glb");
  nlohmann::json tileset = read_json(dir / "tileset.json");
  tileset["root"]["children"][0]["geometricError"] = 1e6;
  test::write_text(dir / "tileset.json", tileset.dump());
  const TilesetCheckReport r = check_tileset(dir);
  EXPECT_TRUE(any_error_mentions(r, "t0_26040_274424.glb: not a valid glb"));
  EXPECT_TRUE(any_error_mentions(r, "t0_26044_274428.glb: missing"));
  EXPECT_TRUE(any_error_mentions(r, "exceeds its parent's"));
  EXPECT_THROW(check_tileset(tmp / "nowhere"), InputError);
}

}  // namespace
}  // namespace citymesh
