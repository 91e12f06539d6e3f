// SPDX-License-Identifier: MIT
#include "citymesh/io/mesh_io.h"

#include <cmath>
#include <span>

#include <fmt/format.h>

#include "citymesh/core/error.h"
#include "citymesh/core/log.h"

namespace citymesh {

void append_vertex_chunk(Mesh& mesh, const PlyVertexChunk& chunk) {
  for (const Vec3d& p : chunk.positions) mesh.positions.push_back(to_local(p, mesh.origin));
  for (const Vec3d& s : chunk.sensor_positions) mesh.sensor_positions.push_back(to_local(s, mesh.origin));
  mesh.times.insert(mesh.times.end(), chunk.times.begin(), chunk.times.end());
  mesh.intensities.insert(mesh.intensities.end(), chunk.intensities.begin(), chunk.intensities.end());
  mesh.colors.insert(mesh.colors.end(), chunk.colors.begin(), chunk.colors.end());
}

void check_frame_reach(const std::filesystem::path& path, std::uint64_t face, std::uint64_t v, const Vec3f& local,
                       const Vec3d& origin) {
  const Vec3d at(local);
  if (dot(at, at) <= kMaxFrameReach * kMaxFrameReach) return;
  throw InputError(fmt::format(
      "{}: face {}: vertex {} lies {:.0f} m from the frame origin ({:.3f}, {:.3f}, {:.3f}), beyond the {:.0f} m "
      "one frame of floats holds (a corrupt first vertex, or acquisitions in different CRSs?)",
      path.string(), face, v, norm(at), origin.x, origin.y, origin.z, kMaxFrameReach));
}

namespace {

void append_faces(Mesh& mesh, const PlyFaceChunk& chunk, std::uint32_t acquisition) {
  for (std::size_t t = 0; t < chunk.triangles.size(); ++t) {
    mesh.triangles.push_back(chunk.triangles[t]);
    mesh.triangle_ids.push_back({acquisition, chunk.fans[t], chunk.faces[t]});
  }
}

/// Removes triangles whose area is (numerically) zero, measured on the file's coordinates
/// `absolute` (as the tiler measures it); returns how many.
std::uint64_t drop_zero_area(Mesh& mesh, std::span<const Vec3d> absolute, double min_doubled_area) {
  std::size_t kept = 0;
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const Triangle& tri = mesh.triangles[t];
    if (degenerate_input_triangle(absolute[tri[0]], absolute[tri[1]], absolute[tri[2]], min_doubled_area)) continue;
    mesh.triangles[kept] = tri;
    mesh.triangle_ids[kept] = mesh.triangle_ids[t];
    ++kept;
  }
  const std::uint64_t dropped = mesh.triangles.size() - kept;
  mesh.triangles.resize(kept);
  mesh.triangle_ids.resize(kept);
  return dropped;
}

/// Throws InputError naming the file and face when a face uses a vertex farther than
/// kMaxFrameReach from the frame origin (its float position has lost its millimetres, or is
/// infinite: a corrupt first vertex, which sets the origin, or an acquisition in another CRS
/// than the first), or has an edge longer than kMaxReach. Unused vertices are not checked:
/// they never reach a result. The frame comes first: beyond it the corners are not the file's.
void check_faces(const std::filesystem::path& path, const Mesh& mesh) {
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const std::uint64_t face = mesh.triangle_ids[t].face;
    for (const std::uint32_t v : mesh.triangles[t]) check_frame_reach(path, face, v, mesh.positions[v], mesh.origin);
    const std::array<Vec3d, 3> c = mesh.corners(t);
    check_face_extent(path, face, c[0], c[1], c[2]);
  }
}

}  // namespace

MeshReadResult read_mesh(const std::filesystem::path& path, const MeshReadParams& params) {
  PlyReader reader(path, params.ply);
  if (params.require_faces) check_has_faces(path, reader.header());
  MeshReadResult result;
  Mesh& mesh = result.mesh;
  mesh.positions.reserve(reader.vertex_count());
  std::vector<Vec3d> absolute;  // the file's coordinates, until the degenerate triangles are found
  absolute.reserve(reader.vertex_count());
  bool origin_set = params.origin.has_value();
  if (origin_set) mesh.origin = *params.origin;
  PlyVertexChunk vertices;
  PlyFaceChunk faces;
  for (auto kind = reader.next(vertices, faces); kind != PlyReader::ChunkKind::end;
       kind = reader.next(vertices, faces)) {
    if (kind == PlyReader::ChunkKind::vertices) {
      if (!origin_set && !vertices.positions.empty()) {
        mesh.origin = whole_metre_origin(vertices.positions.front());
        origin_set = true;
      }
      append_vertex_chunk(mesh, vertices);
      absolute.insert(absolute.end(), vertices.positions.begin(), vertices.positions.end());
    } else {
      append_faces(mesh, faces, params.acquisition);
    }
  }
  result.stats = reader.stats();
  check_faces(path, mesh);
  result.zero_area_dropped = drop_zero_area(mesh, absolute, params.min_doubled_area);
  if (result.zero_area_dropped > 0) {
    log::info("{}: dropped {} zero-area triangles", path.string(), result.zero_area_dropped);
  }
  return result;
}

}  // namespace citymesh
