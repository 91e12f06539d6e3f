// SPDX-License-Identifier: MIT
#include "tileset_output.h"

#include <fmt/format.h>

#include <cstring>
#include <iostream>
#include <map>

#include "citymesh/core/atomic_file.h"
#include "citymesh/core/error.h"
#include "citymesh/core/interrupt.h"
#include "citymesh/core/log.h"
#include "citymesh/core/parallel.h"
#include "citymesh/core/stopwatch.h"
#include "citymesh/io/ply_writer.h"
#include "citymesh/tiles3d/export.h"
#include "kept_files.h"
#include "leaf_outputs.h"
#include "mosaic_output.h"

namespace citymesh::app {

namespace {

TileGridParams grid_params(const Config& config) {
  return {.tile_size = config.tiling.tile_size, .halo = config.tiling.halo, .origin = config.tiling.origin};
}

/// Prints the export's line and returns its figures for the run report.
nlohmann::json report_3d_tiles(const TilesetExportStats& s, const TilesetExportParams& params) {
  std::cout << fmt::format(
      "3D Tiles: {} tiles ({} leaves, {} levels) of {} triangles, {:.1f} bytes per leaf triangle, "
      "{}-bit positions ({:.2f} mm step), {:.2f} s -> {}\n",
      s.tiles, s.leaves, s.levels, s.leaf_triangles,
      static_cast<double>(s.glb_bytes) / static_cast<double>(std::max<std::uint64_t>(s.all_triangles, 1)),
      s.position_bits, s.quantization_step * 1e3, s.seconds, (params.dir / "tileset.json").string());
  return {{"tiles", s.tiles},
          {"leaves", s.leaves},
          {"levels", s.levels},
          {"json_files", s.json_files},
          {"leaf_triangles", s.leaf_triangles},
          {"all_triangles", s.all_triangles},
          {"glb_bytes", s.glb_bytes},
          {"position_bits", s.position_bits},
          {"quantization_step_m", s.quantization_step},
          {"origin", {{"lat", s.origin.lat}, {"lon", s.origin.lon}, {"height", s.origin.height}}},
          {"seconds", s.seconds}};
}

/// The triangles `keep` of `mesh`, with only the vertices they use.
Mesh sub_mesh(const Mesh& mesh, std::span<const std::uint32_t> keep) {
  Mesh out;
  out.origin = mesh.origin;
  std::map<std::uint32_t, std::uint32_t> remap;
  auto vertex = [&](std::uint32_t v) {
    const auto [it, added] = remap.try_emplace(v, static_cast<std::uint32_t>(out.positions.size()));
    if (added) append_vertex(mesh, v, out);
    return it->second;
  };
  for (const std::uint32_t t : keep) {
    const Triangle& tri = mesh.triangles[t];
    out.triangles.push_back({vertex(tri[0]), vertex(tri[1]), vertex(tri[2])});
    out.triangle_ids.push_back(mesh.triangle_ids[t]);
  }
  return out;
}

nlohmann::json write_3d_tiles(const Config& config, const MergedMesh& merged) {
  const TilesetExportParams params = tileset_export_params(config);
  const Crs crs = config.crs();
  return report_3d_tiles(export_tileset({merged.mesh, merged.source_acq, crs}, params), params);
}

/// The output's tiles, as the export reads them.
class LeavesToExport final : public TilesetLeaves {
 public:
  explicit LeavesToExport(const OutputLeaves& leaves) : leaves_(leaves) {
    for (std::size_t l = 0; l < leaves.leaves().size(); ++l) index_[leaves.leaves()[l].key] = l;
  }
  [[nodiscard]] std::vector<TileKey> keys() const override {
    std::vector<TileKey> out;
    for (const OutputLeaf& leaf : leaves_.leaves()) out.push_back(leaf.key);
    return out;
  }
  [[nodiscard]] Box3d box() const override { return leaves_.box(); }
  /// The positions the first pass mapped (local_box), read back: each vertex is mapped once.
  [[nodiscard]] TileMesh leaf(const TileKey& key, const LocalMapping& /*to_local*/) const override {
    throw_if_interrupted("the 3D Tiles export");
    const std::size_t l = index_.at(key);
    const std::string mapped = leaves_.kept(l, kMapped);
    std::vector<Vec3f> local(mapped.size() / sizeof(Vec3f));
    if (!local.empty()) std::memcpy(local.data(), mapped.data(), local.size() * sizeof(Vec3f));
    return tile_mesh(leaves_.load(l), local);
  }
  /// Maps the tile's vertices (all its triangles' own), keeps them beside it for leaf(), and
  /// returns their box.
  [[nodiscard]] Box3d local_box(const TileKey& key, const LocalMapping& to_local) const override {
    const std::size_t l = index_.at(key);
    const std::vector<Vec3f> local = to_local(leaves_.load(l).positions);
    Box3d box;
    for (const Vec3f& p : local) box.extend(Vec3d(p));
    leaves_.keep(l, kMapped, {reinterpret_cast<const char*>(local.data()), local.size() * sizeof(Vec3f)});
    return box;
  }

 private:
  static constexpr std::string_view kMapped = "local";
  const OutputLeaves& leaves_;
  std::map<TileKey, std::size_t> index_;
};

nlohmann::json write_tile_plys(const Config& config, const MergedMesh& merged) {
  Stopwatch clock;
  const std::vector<TileKey> keys = leaf_keys(merged.mesh, TileGrid(grid_params(config)));
  std::map<TileKey, std::vector<std::uint32_t>> tiles;
  for (std::size_t t = 0; t < keys.size(); ++t) tiles[keys[t]].push_back(static_cast<std::uint32_t>(t));
  const std::vector<std::int32_t> faces = source_faces(merged);
  const std::vector<std::int32_t> sources = as_listed(merged.source_acq, config.listed_indices());
  const std::filesystem::path dir = config.project.output / "ply";
  const std::filesystem::path staged = staging_directory(dir);
  std::filesystem::remove_all(staged);
  for (const auto& [key, triangles] : tiles) {
    std::vector<std::int32_t> acq, face;
    for (const std::uint32_t t : triangles) {
      acq.push_back(sources[t]);
      face.push_back(faces[t]);
    }
    write_mesh_ply(staged / (key.name() + ".ply"), sub_mesh(merged.mesh, triangles),
                   {{kSourceAcqProperty, std::span<const std::int32_t>(acq)},
                    {"source_face", std::span<const std::int32_t>(face)}});
  }
  replace_directory_atomically(staged, dir);
  std::cout << fmt::format("provenance PLY: {} tiles -> {}\n", tiles.size(), dir.string());
  return {{"files", tiles.size()}, {"seconds", clock.seconds()}};
}

/// One provenance PLY per tile from the output's tiles in files, each tile's written where
/// `plys` says (empty: on this process's threads).
nlohmann::json write_tile_plys(const Config& config, const OutputLeaves& leaves, const LeafPlyWork& plys) {
  Stopwatch clock;
  const std::filesystem::path dir = config.project.output / "ply";
  const std::filesystem::path staged = staging_directory(dir);
  std::filesystem::remove_all(staged);
  std::filesystem::create_directories(staged);
  const std::vector<std::int32_t> listed = config.listed_indices();
  std::vector<std::filesystem::path> files;
  for (const OutputLeaf& leaf : leaves.leaves()) files.push_back(staged / (leaf.key.name() + ".ply"));
  const std::function<void(std::size_t)> here = [&](std::size_t l) { write_leaf_ply(leaves, l, files[l], listed); };
  if (plys) {
    plys(files, here);
  } else {
    parallel_for_blocks(files.size(), 1, [&](std::size_t begin, std::size_t end) {
      for (std::size_t l = begin; l < end; ++l) here(l);
    });
  }
  replace_directory_atomically(staged, dir);
  std::cout << fmt::format("provenance PLY: {} tiles -> {}\n", leaves.leaves().size(), dir.string());
  return {{"files", leaves.leaves().size()}, {"seconds", clock.seconds()}};
}

/// Removes what this run does not write of the tileset outputs (remove_earlier_output): the
/// folders are citymesh's own (the tileset or the per-tile PLYs, each replaced whole when
/// written).
void remove_unwritten_outputs(const Config& config, bool empty) {
  const std::filesystem::path& out = config.project.output;
  if (empty || !config.output.tiles_3d)
    remove_earlier_output(out / "tiles", empty ? "the output has no triangles" : "[output] tiles_3d = false");
  if (empty || !config.output.ply)
    remove_earlier_output(out / "ply", empty ? "the output has no triangles" : "[output] ply = false");
}

}  // namespace

std::filesystem::path find_tileset(const std::filesystem::path& given) {
  for (const std::filesystem::path& candidate : {given / "tiles" / "tileset.json", given / "tileset.json", given}) {
    if (std::filesystem::is_regular_file(candidate)) return candidate;
  }
  throw InputError(
      fmt::format("{}: no tileset.json there nor in its tiles/ folder (run citymesh run first)", given.string()));
}

void write_leaf_ply(const OutputLeaves& leaves, std::size_t l, const std::filesystem::path& file,
                    std::span<const std::int32_t> listed) {
  throw_if_interrupted("the per-tile PLYs");
  const KeyedPiece piece = leaves.load(l);
  const MeshVertexRows rows = piece_rows(piece);
  const Provenance provenance(piece, listed);
  write_ply(file, {rows.positions, piece.triangles, rows.columns(), provenance.columns(), {std::string(kPlyComment)}});
}

nlohmann::json write_tileset_outputs(const Config& config, const OutputLeaves& leaves, const ExportWork& work,
                                     const LeafPlyWork& plys) {
  nlohmann::json report = nlohmann::json::object();
  remove_unwritten_outputs(config, leaves.leaves().empty());
  if (leaves.leaves().empty()) {
    if (config.output.tiles_3d || config.output.ply) log::warn("the output has no triangles: no tileset written");
    return report;
  }
  if (config.output.tiles_3d) {
    // The encoded tiles and simplified parents stay in the work folder: the next run (an
    // acquisition appended) encodes again only the tiles whose meshes changed, and simplifies
    // again only the parents whose children changed.
    ExportCaches cache(config.project.work);
    const auto started = std::filesystem::file_time_type::clock::now();
    TilesetExportParams params = tileset_export_params(config);
    params.primitives = &cache.primitives;
    params.tree.simplified = &cache.simplified;
    report["tiles_3d"] = report_3d_tiles(export_tileset(LeavesToExport(leaves), config.crs(), params, work), params);
    cache.prune(started);
  }
  if (config.output.ply) report["ply"] = write_tile_plys(config, leaves, plys);
  return report;
}

TilesetExportParams tileset_export_params(const Config& config) {
  TilesetExportParams params;
  params.dir = config.project.output / "tiles";
  params.grid = grid_params(config);
  params.tolerance = config.output.draco_tolerance;
  for (const AcquisitionEntry& a : config.acquisitions) params.acquisitions.push_back({a.name, format_iso8601(a.time)});
  return params;
}

std::unique_ptr<TilesetLeaves> export_view(const OutputLeaves& leaves) {
  return std::make_unique<LeavesToExport>(leaves);
}

nlohmann::json write_tileset_outputs(const Config& config, const MergedMesh& merged) {
  nlohmann::json report = nlohmann::json::object();
  remove_unwritten_outputs(config, merged.mesh.triangle_count() == 0);
  if (merged.mesh.triangle_count() == 0) {
    if (config.output.tiles_3d || config.output.ply) log::warn("the output has no triangles: no tileset written");
    return report;
  }
  if (config.output.tiles_3d) report["tiles_3d"] = write_3d_tiles(config, merged);
  if (config.output.ply) report["ply"] = write_tile_plys(config, merged);
  return report;
}

}  // namespace citymesh::app
