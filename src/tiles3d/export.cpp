// SPDX-License-Identifier: MIT
#include "citymesh/tiles3d/export.h"

#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <cmath>

#include "citymesh/core/atomic_file.h"
#include "citymesh/core/error.h"
#include "citymesh/core/parallel.h"
#include "citymesh/core/stopwatch.h"
#include "tileset_json.h"

namespace citymesh {

namespace {

/// Origin of the local frame: the centre of the output's x-y extent at its lowest z, in whole
/// metres so that it reads well and does not depend on float rounding.
Vec3d frame_origin(const Mesh& mesh) {
  Box3d box;
  for (std::size_t v = 0; v < mesh.vertex_count(); ++v) box.extend(mesh.world_position(v));
  return {std::round((box.min.x + box.max.x) / 2), std::round((box.min.y + box.max.y) / 2), std::round(box.min.z)};
}

std::vector<Vec3f> local_positions(const Mesh& mesh, const Crs& crs, const EnuFrame& frame) {
  std::vector<Vec3f> out(mesh.vertex_count());
  parallel_for_blocks(out.size(), 4096, [&](std::size_t begin, std::size_t end) {
    for (std::size_t v = begin; v < end; ++v) out[v] = Vec3f(frame.from_ecef(crs.to_ecef(mesh.world_position(v))));
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

SplitMesh split_by_source(const Mesh& mesh, std::span<const std::int32_t> source_acq, std::span<const Vec3f> local) {
  // The split vertices in (vertex, feature) order. Nearly every vertex has one feature, its
  // smallest; only the pairs beyond it (vertices that stitch triangles share with a source)
  // are listed and sorted. Sorting a key per corner took three times the output's triangle
  // array, twice over: the peak of a city's export.
  constexpr std::uint32_t kUnused = UINT32_MAX;
  auto key = [](std::uint32_t v, std::uint16_t f) { return (std::uint64_t{v} << 16) | f; };
  const std::size_t n = mesh.triangle_count();
  std::vector<std::uint32_t> first(mesh.vertex_count(), kUnused);  ///< per vertex: its smallest feature
  for (std::size_t t = 0; t < n; ++t) {
    const std::uint32_t f = feature_of(source_acq[t]);
    for (const std::uint32_t v : mesh.triangles[t]) first[v] = std::min(first[v], f);
  }
  std::vector<std::uint64_t> extra;  ///< (vertex, feature) pairs beyond the vertex's first, sorted
  for (std::size_t t = 0; t < n; ++t) {
    const std::uint16_t f = feature_of(source_acq[t]);
    for (const std::uint32_t v : mesh.triangles[t]) {
      if (f != first[v]) extra.push_back(key(v, f));
    }
  }
  std::sort(extra.begin(), extra.end());
  extra.erase(std::unique(extra.begin(), extra.end()), extra.end());
  std::vector<std::uint32_t> start(mesh.vertex_count() + 1, 0);  ///< per vertex: its first split vertex
  for (std::size_t v = 0; v < mesh.vertex_count(); ++v) start[v + 1] = first[v] != kUnused ? 1 : 0;
  for (const std::uint64_t k : extra) ++start[(k >> 16) + 1];
  for (std::size_t v = 0; v < mesh.vertex_count(); ++v) start[v + 1] += start[v];
  const auto index = [&](std::uint32_t v, std::uint16_t f) -> std::uint32_t {
    if (f == first[v]) return start[v];
    const auto it = std::lower_bound(extra.begin(), extra.end(), key(v, f));
    const auto v_first = std::lower_bound(extra.begin(), it, key(v, 0));
    return start[v] + 1 + static_cast<std::uint32_t>(it - v_first);
  };
  SplitMesh out;
  TilesetVertices& vx = out.vertices;
  const std::size_t count = start.back();
  vx.positions.resize(count);
  vx.feature_ids.resize(count);
  if (!mesh.intensities.empty()) vx.intensities.resize(count);
  if (!mesh.colors.empty()) vx.colors.resize(count);
  const auto put = [&](std::uint32_t v, std::uint16_t f, std::uint32_t i) {
    vx.positions[i] = local[v];
    vx.feature_ids[i] = f;
    if (!vx.intensities.empty()) vx.intensities[i] = mesh.intensities[v];
    if (!vx.colors.empty()) vx.colors[i] = mesh.colors[v];
  };
  parallel_for_blocks(mesh.vertex_count(), 16384, [&](std::size_t begin, std::size_t end) {
    for (std::size_t v = begin; v < end; ++v) {
      if (first[v] != kUnused) put(static_cast<std::uint32_t>(v), static_cast<std::uint16_t>(first[v]), start[v]);
    }
  });
  for (const std::uint64_t k : extra) {
    const auto v = static_cast<std::uint32_t>(k >> 16);
    const auto f = static_cast<std::uint16_t>(k & 0xFFFF);
    put(v, f, index(v, f));
  }
  out.triangles.resize(n);
  parallel_for_blocks(n, 16384, [&](std::size_t begin, std::size_t end) {
    for (std::size_t t = begin; t < end; ++t) {
      const Triangle& tri = mesh.triangles[t];
      const std::uint16_t f = feature_of(source_acq[t]);
      out.triangles[t] = {index(tri[0], f), index(tri[1], f), index(tri[2], f)};
    }
  });
  return out;
}

/// The Draco lattice covering every vertex, with bits for the tolerance.
DracoEncodeParams shared_lattice(std::span<const Vec3f> positions, const TilesetExportParams& params) {
  Box3d box;
  for (const Vec3f& p : positions) box.extend(Vec3d(p));
  // Whole metres, one metre of margin: exact in float, the same whatever the tile.
  const Vec3d lo{std::floor(box.min.x) - 1, std::floor(box.min.y) - 1, std::floor(box.min.z) - 1};
  const double range = std::ceil(std::max({box.max.x - lo.x, box.max.y - lo.y, box.max.z - lo.z})) + 1;
  // Rounding moves a position by at most half a step: step = range / (2^bits - 1) <= 2 tolerance.
  const double levels = range / (2 * params.tolerance);
  const int bits = std::max(1, static_cast<int>(std::ceil(std::log2(levels + 1))));
  if (bits > 30) {
    throw ConfigError(fmt::format("output.draco_tolerance {} m is too fine for an output {} m across "
                                  "(Draco quantizes to at most 30 bits)", params.tolerance, range));
  }
  DracoEncodeParams draco;
  draco.position_bits = bits;
  draco.speed = params.draco_speed;
  draco.lattice = DracoLattice{{static_cast<float>(lo.x), static_cast<float>(lo.y), static_cast<float>(lo.z)},
                               static_cast<float>(range)};
  return draco;
}

/// The tile's own vertex attributes, gathered from the shared buffer.
struct TileAttributes {
  std::vector<Vec3f> positions;
  std::vector<std::uint16_t> feature_ids;
  std::vector<float> intensities;
  std::vector<Rgb8> colors;
};

TileAttributes gather(const TilesetVertices& all, const TileMesh& mesh) {
  TileAttributes a;
  for (const std::uint32_t v : mesh.vertices) {
    a.positions.push_back(all.positions[v]);
    a.feature_ids.push_back(all.feature_ids[v]);
    if (!all.intensities.empty()) a.intensities.push_back(all.intensities[v]);
    if (!all.colors.empty()) a.colors.push_back(all.colors[v]);
  }
  return a;
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

TilesetExportStats export_tileset(const TilesetSource& source, const TilesetExportParams& params) {
  Stopwatch clock;
  const Mesh& mesh = source.mesh;
  if (mesh.triangle_count() == 0) throw ProcessingError("3D Tiles: the output has no triangles to export");
  if (source.source_acq.size() != mesh.triangle_count()) {
    throw ProcessingError("3D Tiles: one source acquisition per triangle is needed");
  }
  TilesetExportStats stats;
  stats.origin = source.crs.to_geodetic(frame_origin(mesh));
  const EnuFrame frame(stats.origin);
  // The positions in the local frame live only while the split copies them.
  const SplitMesh split = split_by_source(mesh, source.source_acq, local_positions(mesh, source.crs, frame));
  GlbParams glb{.draco = params.draco, .draco_params = shared_lattice(split.vertices.positions, params),
                .acquisitions = params.acquisitions};
  const double step = static_cast<double>(glb.draco_params.lattice->range) /
                      static_cast<double>((std::uint64_t{1} << glb.draco_params.position_bits) - 1);

  const std::filesystem::path staged = staging_directory(params.dir);
  std::error_code ec;
  std::filesystem::remove_all(staged, ec);
  std::filesystem::create_directories(staged, ec);
  if (ec) throw OutputError(fmt::format("{}: cannot create the folder: {}", staged.string(), ec.message()));
  // Each tile is written as soon as the tree is done with it, and its mesh freed: holding
  // every tile until the last was built was the peak of a city's final pass.
  std::atomic<std::uint64_t> glb_bytes{0};
  const auto write_tile = [&](const TileNode& node) {
    if (node.mesh.triangles.empty()) return;
    const TileAttributes a = gather(split.vertices, node.mesh);
    const std::vector<std::uint8_t> content =
        write_glb({a.positions, node.mesh.triangles, a.feature_ids, a.intensities, a.colors}, glb);
    write_file_atomically(staged / (node.name() + ".glb"),
                          {reinterpret_cast<const char*>(content.data()), content.size()});
    glb_bytes += content.size();
  };
  const TileTree tree = build_tile_tree(split.vertices, split.triangles, leaf_keys(mesh, TileGrid(params.grid)),
                                        params.tree, write_tile);
  const auto files = tileset_json_files(tree, {.transform = frame.to_ecef_matrix(),
                                               .max_tiles_per_file = params.max_tiles_per_file,
                                               .box_margin = step,
                                               .min_half_extent = 0.01});
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
  stats.position_bits = glb.draco_params.position_bits;
  stats.quantization_step = step;
  stats.seconds = clock.seconds();
  return stats;
}

}  // namespace citymesh
