// SPDX-License-Identifier: MIT
#include "citymesh/tiles3d/export.h"

#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <optional>
#include <set>

#include "citymesh/core/atomic_file.h"
#include "citymesh/core/checksum.h"
#include "citymesh/core/error.h"
#include "citymesh/core/log.h"
#include "citymesh/core/parallel.h"
#include "citymesh/core/progress.h"
#include "citymesh/core/read_file.h"
#include "citymesh/core/stopwatch.h"
#include "citymesh/geo/local_frame_map.h"
#include "tileset_json.h"

namespace citymesh {

namespace {

/// Origin of the local frame: the centre of the output's x-y extent at its lowest z, in whole
/// metres so that it reads well and does not depend on float rounding.
Vec3d frame_origin(const Box3d& box) {
  return {std::round((box.min.x + box.max.x) / 2), std::round((box.min.y + box.max.y) / 2), std::round(box.min.z)};
}

Box3d world_box(const Mesh& mesh) {
  Box3d box;
  for (std::size_t v = 0; v < mesh.vertex_count(); ++v) box.extend(mesh.world_position(v));
  return box;
}

std::vector<Vec3f> local_positions(const Mesh& mesh, const Crs& crs, const EnuFrame& frame) {
  std::vector<Vec3f> out(mesh.vertex_count());
  parallel_for_blocks(out.size(), 16384, [&](std::size_t begin, std::size_t end) {
    std::vector<Vec3d> world;
    for (std::size_t v = begin; v < end; ++v) world.push_back(mesh.world_position(v));
    std::ranges::copy(map_to_local_frame(world, crs, frame), out.begin() + static_cast<std::ptrdiff_t>(begin));
  });
  return out;
}

/// One vertex per (input vertex, source acquisition) pair, so that every vertex has one
/// feature id; triangles re-indexed onto the split vertices.
struct SplitMesh {
  TilesetVertices vertices;
  std::vector<Triangle> triangles;
};

std::uint16_t feature_of(std::int32_t source) {
  if (source >= kNullFeatureId) {
    throw ProcessingError(fmt::format("3D Tiles: acquisition {} does not fit a 16-bit feature id", source));
  }
  return source < 0 ? kNullFeatureId : static_cast<std::uint16_t>(source);
}

/// One vertex per (vertex, feature) pair the triangles draw, in (vertex, feature) order
/// (vertices no triangle uses are left out), and the triangles re-indexed onto them.
struct FeatureSplit {
  std::vector<std::uint32_t> vertex;   ///< per split vertex: the vertex it copies
  std::vector<std::uint16_t> feature;  ///< per split vertex
  std::vector<Triangle> triangles;
};

/// `features`: one per triangle. Nearly every vertex has one feature, its smallest; only the
/// pairs beyond it (vertices that stitch triangles share with a source) are listed and
/// sorted. Sorting a key per corner took three times the output's triangle array, twice over
/// (the peak of a city's export), and a sixth of the time a leaf of the export took to load.
FeatureSplit split_by_feature(std::size_t vertex_count, std::span<const Triangle> triangles,
                              std::span<const std::uint16_t> features) {
  constexpr std::uint32_t kUnused = UINT32_MAX;
  auto key = [](std::uint32_t v, std::uint16_t f) { return (std::uint64_t{v} << 16) | f; };
  const std::size_t n = triangles.size();
  std::vector<std::uint32_t> first(vertex_count, kUnused);  ///< per vertex: its smallest feature
  for (std::size_t t = 0; t < n; ++t) {
    for (const std::uint32_t v : triangles[t]) first[v] = std::min<std::uint32_t>(first[v], features[t]);
  }
  std::vector<std::uint64_t> extra;  ///< (vertex, feature) pairs beyond the vertex's first, sorted
  for (std::size_t t = 0; t < n; ++t) {
    for (const std::uint32_t v : triangles[t]) {
      if (features[t] != first[v]) extra.push_back(key(v, features[t]));
    }
  }
  std::sort(extra.begin(), extra.end());
  extra.erase(std::unique(extra.begin(), extra.end()), extra.end());
  std::vector<std::uint32_t> start(vertex_count + 1, 0);  ///< per vertex: its first split vertex
  for (std::size_t v = 0; v < vertex_count; ++v) start[v + 1] = first[v] != kUnused ? 1 : 0;
  for (const std::uint64_t k : extra) ++start[(k >> 16) + 1];
  for (std::size_t v = 0; v < vertex_count; ++v) start[v + 1] += start[v];
  const auto index = [&](std::uint32_t v, std::uint16_t f) -> std::uint32_t {
    if (f == first[v]) return start[v];
    const auto it = std::lower_bound(extra.begin(), extra.end(), key(v, f));
    const auto v_first = std::lower_bound(extra.begin(), it, key(v, 0));
    return start[v] + 1 + static_cast<std::uint32_t>(it - v_first);
  };
  FeatureSplit out;
  const std::size_t count = start.back();
  out.vertex.resize(count);
  out.feature.resize(count);
  parallel_for_blocks(vertex_count, 16384, [&](std::size_t begin, std::size_t end) {
    for (std::size_t v = begin; v < end; ++v) {
      if (first[v] == kUnused) continue;
      out.vertex[start[v]] = static_cast<std::uint32_t>(v);
      out.feature[start[v]] = static_cast<std::uint16_t>(first[v]);
    }
  });
  for (const std::uint64_t k : extra) {
    const auto v = static_cast<std::uint32_t>(k >> 16);
    const auto f = static_cast<std::uint16_t>(k & 0xFFFF);
    out.vertex[index(v, f)] = v;
    out.feature[index(v, f)] = f;
  }
  out.triangles.resize(n);
  parallel_for_blocks(n, 16384, [&](std::size_t begin, std::size_t end) {
    for (std::size_t t = begin; t < end; ++t) {
      const Triangle& tri = triangles[t];
      out.triangles[t] = {index(tri[0], features[t]), index(tri[1], features[t]), index(tri[2], features[t])};
    }
  });
  return out;
}

std::vector<std::uint16_t> triangle_features(std::span<const std::int32_t> source_acq) {
  std::vector<std::uint16_t> out(source_acq.size());
  for (std::size_t t = 0; t < out.size(); ++t) out[t] = feature_of(source_acq[t]);
  return out;
}

SplitMesh split_by_source(const Mesh& mesh, std::span<const std::int32_t> source_acq, std::span<const Vec3f> local) {
  FeatureSplit split = split_by_feature(mesh.vertex_count(), mesh.triangles, triangle_features(source_acq));
  SplitMesh out;
  TilesetVertices& vx = out.vertices;
  const std::size_t count = split.vertex.size();
  vx.positions.resize(count);
  vx.feature_ids = std::move(split.feature);
  if (!mesh.intensities.empty()) vx.intensities.resize(count);
  if (!mesh.colors.empty()) vx.colors.resize(count);
  parallel_for_blocks(count, 16384, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      const std::uint32_t v = split.vertex[i];
      vx.positions[i] = local[v];
      if (!vx.intensities.empty()) vx.intensities[i] = mesh.intensities[v];
      if (!vx.colors.empty()) vx.colors[i] = mesh.colors[v];
    }
  });
  out.triangles = std::move(split.triangles);
  return out;
}

Box3d positions_box(std::span<const Vec3f> positions) {
  Box3d box;
  for (const Vec3f& p : positions) box.extend(Vec3d(p));
  return box;
}

/// The Draco lattice covering `box` (every vertex, in the local frame), with bits for the
/// tolerance.
DracoEncodeParams shared_lattice(const Box3d& box, const TilesetExportParams& params) {
  // Whole metres, one metre of margin: exact in float, the same whatever the tile.
  const Vec3d lo{std::floor(box.min.x) - 1, std::floor(box.min.y) - 1, std::floor(box.min.z) - 1};
  const double range = std::ceil(std::max({box.max.x - lo.x, box.max.y - lo.y, box.max.z - lo.z})) + 1;
  // Rounding moves a position by at most half a step: step = range / (2^bits - 1) <= 2 tolerance.
  const double levels = range / (2 * params.tolerance);
  const int bits = std::max(1, static_cast<int>(std::ceil(std::log2(levels + 1))));
  if (bits > 30) {
    throw ConfigError(
        fmt::format("output.draco_tolerance {} m is too fine for an output {} m across "
                    "(Draco quantizes to at most 30 bits)",
                    params.tolerance, range));
  }
  DracoEncodeParams draco;
  draco.position_bits = bits;
  draco.speed = params.draco_speed;
  draco.lattice = DracoLattice{{static_cast<float>(lo.x), static_cast<float>(lo.y), static_cast<float>(lo.z)},
                               static_cast<float>(range)};
  return draco;
}

/// A tile's feature ids: its vertices' keys carry them.
std::vector<std::uint16_t> feature_ids(const TileMesh& mesh) {
  std::vector<std::uint16_t> out;
  out.reserve(mesh.vertex_count());
  for (const TileVertexKey& k : mesh.keys) out.push_back(k.feature);
  return out;
}

/// Tiles on the longest path from the root to a leaf (a parent may skip levels of the grid).
std::size_t tree_depth(const TileTree& tree) {
  std::vector<std::size_t> depth(tree.nodes.size(), 1);
  for (std::size_t n = 0; n < tree.nodes.size(); ++n) {  // children come before their parents
    for (const std::uint32_t c : tree.nodes[n].children) depth[n] = std::max(depth[n], depth[c] + 1);
  }
  return depth.back();
}

}  // namespace

std::vector<TileKey> leaf_keys(const Mesh& mesh, const TileGrid& grid) {
  std::vector<TileKey> keys(mesh.triangle_count());
  for (std::size_t t = 0; t < keys.size(); ++t) {
    const Triangle& tri = mesh.triangles[t];
    const Vec3d centroid =
        (mesh.world_position(tri[0]) + mesh.world_position(tri[1]) + mesh.world_position(tri[2])) * (1.0 / 3.0);
    keys[t] = grid.owner(centroid);
  }
  return keys;
}

namespace {

/// Writes tiles' glb files into an export's staging folder.
class TileWriter {
 public:
  TileWriter(const TilesetFrame& frame, const TilesetExportParams& params)
      : glb_{.draco = params.draco,
             .draco_params = frame.lattice,
             .acquisitions = params.acquisitions,
             .primitives = params.primitives},
        staged_(staging_directory(params.dir)) {}

  /// Writes `node`'s tile (none when it has no triangles); returns its bytes.
  std::uint64_t write(const TileNode& node) const {
    if (node.mesh.triangles.empty()) return 0;
    const TileMesh& m = node.mesh;
    const std::vector<std::uint8_t> content =
        write_glb({m.positions, m.triangles, feature_ids(m), m.intensities, m.colors}, glb_);
    write_file_atomically(staged_ / (node.name() + ".glb"),
                          {reinterpret_cast<const char*>(content.data()), content.size()});
    return content.size();
  }

 private:
  GlbParams glb_;
  std::filesystem::path staged_;
};

/// A digest of every tile's glb (its name and bytes, in the order of the names: the tree's
/// order of nodes depends on how the work was split): the tileset's version, which changes
/// exactly when a tile does. Viewers that honour it add it to their requests, so that an
/// updated map is not hidden behind their caches. Read back from `staged`: under MPI other
/// ranks write some of the tiles.
std::string content_version(const TileTree& tree, const std::filesystem::path& staged) {
  std::vector<std::string> names;
  for (const TileNode& node : tree.nodes) {
    if (node.triangle_count > 0) names.push_back(node.name() + ".glb");
  }
  std::sort(names.begin(), names.end());
  BulkChecksum sum;
  for (const std::string& name : names) {
    const std::optional<std::string> bytes = read_file_bytes(staged / name);
    if (!bytes) throw OutputError(fmt::format("{}: the tile written is missing", (staged / name).string()));
    sum.add(name.data(), name.size());
    sum.add(bytes->data(), bytes->size());
  }
  return fmt::format("{:016x}", sum.value());
}

/// Builds the tree with `build` (given the sink that writes each tile) and writes the tileset:
/// the glb of every tile as the tree hands it over, then the JSON files.
TilesetExportStats write_tileset(const TilesetFrame& frame, const TilesetExportParams& params,
                                 const std::function<TileTree(const TileNodeSink&)>& build) {
  Stopwatch clock;
  TilesetExportStats stats;
  stats.origin = frame.origin;
  const EnuFrame enu(frame.origin);
  const double step = static_cast<double>(frame.lattice.lattice->range) /
                      static_cast<double>((std::uint64_t{1} << frame.lattice.position_bits) - 1);
  const std::filesystem::path staged = staging_directory(params.dir);
  std::error_code ec;
  std::filesystem::remove_all(staged, ec);
  std::filesystem::create_directories(staged, ec);
  if (ec) throw OutputError(fmt::format("{}: cannot create the folder: {}", staged.string(), ec.message()));
  // Each tile is written as soon as the tree is done with it, and its mesh freed: holding
  // every tile until the last was built was the peak of a city's final pass.
  const TileWriter writer(frame, params);
  std::atomic<std::uint64_t> glb_bytes{0};
  const TileTree tree = build([&](const TileNode& node) { glb_bytes += writer.write(node); });
  const auto files = tileset_json_files(tree, {.transform = enu.to_ecef_matrix(),
                                               .max_tiles_per_file = params.max_tiles_per_file,
                                               .box_margin = step,
                                               .min_half_extent = 0.01,
                                               .tileset_version = content_version(tree, staged)});
  for (const auto& [name, text] : files) write_file_atomically(staged / name, text);
  replace_directory_atomically(staged, params.dir);

  stats.tiles = tree.nodes.size();
  stats.json_files = files.size();
  stats.levels = tree_depth(tree);
  for (const TileNode& node : tree.nodes) {
    stats.all_triangles += node.triangle_count;
    if (node.level == 0) {
      ++stats.leaves;
      stats.leaf_triangles += node.triangle_count;
    }
  }
  stats.glb_bytes = glb_bytes.load();
  stats.position_bits = frame.lattice.position_bits;
  stats.quantization_step = step;
  stats.seconds = clock.seconds();
  return stats;
}

LocalMapping local_mapping(const Crs& crs, const EnuFrame& frame) {
  return [&crs, &frame](std::span<const Vec3d> positions) { return map_to_local_frame(positions, crs, frame); };
}

}  // namespace

TilesetExportStats export_tileset(const TilesetSource& source, const TilesetExportParams& params) {
  Stopwatch clock;
  const Mesh& mesh = source.mesh;
  if (mesh.triangle_count() == 0) throw ProcessingError("3D Tiles: the output has no triangles to export");
  if (source.source_acq.size() != mesh.triangle_count()) {
    throw ProcessingError("3D Tiles: one source acquisition per triangle is needed");
  }
  const Geodetic origin = source.crs.to_geodetic(frame_origin(world_box(mesh)));
  const EnuFrame frame(origin);
  // The positions in the local frame live only while the split copies them.
  const SplitMesh split = split_by_source(mesh, source.source_acq, local_positions(mesh, source.crs, frame));
  TilesetExportStats stats = write_tileset(
      {origin, shared_lattice(positions_box(split.vertices.positions), params)}, params, [&](const TileNodeSink& sink) {
        return build_tile_tree(split.vertices, split.triangles, leaf_keys(mesh, TileGrid(params.grid)), params.tree,
                               sink);
      });
  stats.seconds = clock.seconds();
  return stats;
}

TilesetExportStats export_tileset(const TilesetLeaves& leaves, const Crs& crs, const TilesetExportParams& params,
                                  const ExportWork& work) {
  Stopwatch clock;
  const std::vector<TileKey> keys = leaves.keys();
  if (keys.empty()) throw ProcessingError("3D Tiles: the output has no triangles to export");
  const Geodetic origin = crs.to_geodetic(frame_origin(leaves.box()));
  const EnuFrame enu(origin);
  const LocalMapping to_local = local_mapping(crs, enu);
  // The lattice must hold every vertex in the local frame, whose box only the leaves know: one
  // pass over them first, a leaf at a time.
  const std::function<Box3d(std::size_t)> map_here = [&](std::size_t k) { return leaves.local_box(keys[k], to_local); };
  const std::vector<Box3d> boxes =
      work.boxes ? work.boxes(origin, keys, map_here) : parallel_map(keys.size(), map_here);
  if (boxes.size() != keys.size()) {
    throw ProcessingError(fmt::format("3D Tiles: {} boxes for {} leaves", boxes.size(), keys.size()));
  }
  Box3d box;
  for (const Box3d& b : boxes) box.extend(b);
  log::debug("3D Tiles: {} leaves mapped to the local frame in {:.2f} s", keys.size(), clock.seconds());
  const TilesetFrame frame{origin, shared_lattice(box, params)};
  std::uint64_t cell_bytes = 0;
  TilesetExportStats stats = write_tileset(frame, params, [&](const TileNodeSink& sink) {
    const LeafSource source = [&](const TileKey& key) { return leaves.leaf(key, to_local); };
    std::set<std::pair<int, TileKey>> written;  // the cells' open nodes: export_cell wrote them
    const TileNodeSink unless_written = [&](const TileNode& node) {
      if (!written.contains({node.level, node.key})) sink(node);
    };
    const TileTreeBuild tree(keys, source, params.tree, unless_written);
    // The cells weighed by their leaves: those along the output's edges hold few.
    std::optional<StageProgress> progress;
    if (!work.progress.empty()) {
      progress.emplace(StageProgressParams{
          .stage = work.progress + " cells built", .total = tree.cell_count(), .total_work = keys.size()});
    }
    const std::function<ExportedCell(std::size_t)> here = [&](std::size_t c) {
      ExportedCell cell = export_cell(leaves, crs, frame, params, c);
      if (progress) progress->advance(1, tree.cell_leaves(c).size());
      return cell;
    };
    Stopwatch cells_clock;
    std::vector<ExportedCell> built =
        work.cells ? work.cells(frame, tree, here) : parallel_map(tree.cell_count(), here);
    log::debug("3D Tiles: {} cells built in {:.2f} s", built.size(), cells_clock.seconds());
    if (progress) {
      progress->finish();
      log::info("{}: the levels above the cells", work.progress);
    }
    std::vector<TileSubtree> subtrees;
    for (ExportedCell& e : built) {
      const TileNode& open = e.subtree.nodes.at(e.subtree.open);
      written.emplace(open.level, open.key);
      cell_bytes += e.glb_bytes;
      subtrees.push_back(std::move(e.subtree));
    }
    Stopwatch levels_clock;
    TileTree finished = tree.finish(std::move(subtrees));
    log::debug("3D Tiles: the levels above the cells built in {:.2f} s", levels_clock.seconds());
    return finished;
  });
  stats.glb_bytes += cell_bytes;
  stats.seconds = clock.seconds();
  return stats;
}

Box3d export_leaf_box(const TilesetLeaves& leaves, const Crs& crs, const Geodetic& origin, const TileKey& key) {
  const EnuFrame enu(origin);
  return leaves.local_box(key, local_mapping(crs, enu));
}

ExportedCell export_cell(const TilesetLeaves& leaves, const Crs& crs, const TilesetFrame& frame,
                         const TilesetExportParams& params, std::size_t cell) {
  const EnuFrame enu(frame.origin);
  const LocalMapping to_local = local_mapping(crs, enu);
  const TileWriter writer(frame, params);
  std::atomic<std::uint64_t> bytes{0};
  const TileNodeSink sink = [&](const TileNode& node) { bytes += writer.write(node); };
  const LeafSource source = [&](const TileKey& key) { return leaves.leaf(key, to_local); };
  const std::vector<TileKey> keys = leaves.keys();
  const TileTreeBuild tree(keys, source, params.tree, sink);
  ExportedCell out{tree.build_cell(cell), 0};
  // The open node's mesh is final too (the levels above only read it): written here, where
  // the cell is built, rather than by the process that builds the levels above.
  out.glb_bytes = bytes.load() + writer.write(out.subtree.nodes.at(out.subtree.open));
  return out;
}

Box3d TilesetLeaves::local_box(const TileKey& key, const LocalMapping& to_local) const {
  return positions_box(leaf(key, to_local).positions);
}

TileMesh tile_mesh(const KeyedPiece& piece, const LocalMapping& to_local) {
  return tile_mesh(piece, to_local(piece.positions));
}

TileMesh tile_mesh(const KeyedPiece& piece, std::span<const Vec3f> local) {
  if (local.size() != piece.vertex_count())
    throw ProcessingError(
        fmt::format("3D Tiles: {} mapped positions for a piece of {} vertices", local.size(), piece.vertex_count()));
  // One tile vertex per (vertex, feature) the triangles draw: a vertex shared by two sources
  // is drawn twice, each with its own feature id. The piece's keys ascend, so (key, feature)
  // order is (vertex, feature) order.
  FeatureSplit split = split_by_feature(piece.vertex_count(), piece.triangles, triangle_features(piece.source_acq));
  TileMesh m;
  const std::size_t count = split.vertex.size();
  m.keys.resize(count);
  m.positions.resize(count);
  if (!piece.intensities.empty()) m.intensities.resize(count);
  if (!piece.colors.empty()) m.colors.resize(count);
  for (std::size_t i = 0; i < count; ++i) {
    const std::uint32_t v = split.vertex[i];
    m.keys[i] = {piece.keys[v], split.feature[i]};
    m.positions[i] = local[v];
    if (!piece.intensities.empty()) m.intensities[i] = piece.intensities[v];
    if (!piece.colors.empty()) m.colors[i] = piece.colors[v];
  }
  m.triangles = std::move(split.triangles);
  return m;
}

}  // namespace citymesh
