// SPDX-License-Identifier: MIT
#include "acquisitions.h"

#include <fmt/format.h>

#include "citymesh/core/error.h"
#include "citymesh/core/log.h"
#include "citymesh/geo/crs.h"
#include "citymesh/io/mesh_io.h"
#include "citymesh/io/ply_reader.h"

namespace citymesh::app {

std::vector<std::int32_t> source_faces(const Mesh& m) {
  std::vector<std::int32_t> faces(m.triangle_count());
  for (std::size_t t = 0; t < faces.size(); ++t) faces[t] = static_cast<std::int32_t>(m.triangle_ids[t].face);
  return faces;
}

void check_provenance_ids(const std::filesystem::path& file, std::uint64_t faces) {
  if (faces > std::uint64_t{INT32_MAX}) {
    throw InputError(fmt::format("{}: {} faces; provenance ids are 32-bit (split the file)", file.string(), faces));
  }
}

void check_within_crs_area(const Config& config, const Acquisition& a, const Vec3d& position) {
  const Crs crs = config.crs();
  const AreaOfUse area = crs.area_of_use();
  const Geodetic at = crs.to_lat_lon(position);
  if (area.holds(at)) return;
  throw InputError(fmt::format(
      "{}: a vertex at x {:.2f}, y {:.2f} lies at lat {:.4f}, lon {:.4f}, outside the area {} ({}) is meant for "
      "(lat {}..{}, lon {}..{}): are the file's coordinates in another CRS (longitude and latitude as metres, "
      "another UTM zone)? Set [project] crs to the files' CRS",
      a.path.string(), position.x, position.y, at.lat, at.lon, crs.spec(), crs.name(), area.lat_min, area.lat_max,
      area.lon_min, area.lon_max));
}

void check_acquisition_file(const Config& config, const Acquisition& a) {
  if (a.withdrawn) return;
  PlyReadParams params = config.ply_read_params();
  params.time_names.clear();  // only a position is wanted
  PlyReader reader(a.path, params);
  check_has_faces(a.path, reader.header());
  PlyVertexChunk vertices;
  PlyFaceChunk faces;
  for (auto kind = reader.next(vertices, faces); kind != PlyReader::ChunkKind::end;
       kind = reader.next(vertices, faces)) {
    if (kind == PlyReader::ChunkKind::vertices && !vertices.positions.empty()) {
      check_within_crs_area(config, a, vertices.positions.front());
      return;
    }
  }
}

Mesh read_acquisition(const Config& config, const Acquisition& a, const std::optional<Vec3d>& origin) {
  if (a.withdrawn) {
    log::info("{}: withdrawn, read as an empty mesh", a.path.string());
    Mesh empty;
    empty.origin = origin.value_or(Vec3d{});
    return empty;
  }
  MeshReadParams params;
  params.ply = config.ply_read_params();
  params.acquisition = a.index;
  params.origin = origin;
  params.require_faces = true;
  MeshReadResult r = read_mesh(a.path, params);
  check_provenance_ids(a.path, r.stats.faces);
  if (r.mesh.vertex_count() > 0) check_within_crs_area(config, a, r.mesh.world_position(0));
  log::info("{}: {} triangles", a.path.string(), r.mesh.triangle_count());
  return std::move(r.mesh);
}

LoadedAcquisitions load_acquisitions(const Config& config) {
  LoadedAcquisitions out;
  out.acquisitions = config.acquisition_list();
  if (out.acquisitions.empty()) throw ConfigError(fmt::format("{}: no [[acquisition]]", config.file.string()));
  // Every mesh in the frame of the first one with a vertex: an empty one (withdrawn, say) has
  // none of its own, and later steps take the first mesh's frame as everyone's.
  std::optional<Vec3d> frame;
  for (const Acquisition& a : out.acquisitions) {
    out.meshes.push_back(read_acquisition(config, a, frame));
    if (!frame && out.meshes.back().vertex_count() > 0) frame = out.meshes.back().origin;
    out.dates.push_back(a.date);
  }
  for (Mesh& m : out.meshes) {
    if (m.vertex_count() == 0 && frame) m.origin = *frame;
  }
  return out;
}

nlohmann::json acquisition_json(const Config& config, const LoadedAcquisitions& input, std::size_t k) {
  return {{"index", config.acquisitions[k].listed},
          {"name", config.acquisitions[k].name},
          {"date", format_iso8601(input.dates[k])},
          {"input", input.acquisitions[k].path.string()}};
}

std::vector<std::int32_t> as_listed(std::span<const std::int32_t> source_acq, std::span<const std::int32_t> listed) {
  std::vector<std::int32_t> out(source_acq.size());
  for (std::size_t t = 0; t < out.size(); ++t) {
    const std::int32_t a = source_acq[t];
    if (a >= 0 && static_cast<std::size_t>(a) >= listed.size()) {
      throw ProcessingError(
          fmt::format("outputs: source {} of triangle {} is not among the {} acquisitions", a, t, listed.size()));
    }
    out[t] = a < 0 ? a : listed[static_cast<std::size_t>(a)];
  }
  return out;
}

}  // namespace citymesh::app
