// SPDX-License-Identifier: MIT
#include "face_table.h"

#include "citymesh/io/ply_reader.h"

namespace citymesh::app {

Mesh FaceTable::local_mesh(const Vec3d& origin) const {
  Mesh m;
  m.origin = origin;
  m.positions.reserve(positions.size());
  for (const Vec3d& p : positions) m.positions.push_back(to_local(p, origin));
  m.triangles = triangles;
  m.triangle_ids.resize(triangles.size());
  return m;
}

TriangleCorners FaceTable::corners(std::size_t t) const {
  const Triangle& tri = triangles[t];
  return {positions[tri[0]], positions[tri[1]], positions[tri[2]]};
}

FaceTable read_face_table(const std::filesystem::path& path, const std::vector<std::string>& extra_faces) {
  PlyReadParams params;
  params.require_sensor_origin = false;
  params.extra_face_properties = extra_faces;
  PlyReader reader(path, params);
  PlyVertexChunk vertices;
  PlyFaceChunk faces;
  FaceTable out;
  out.extras.resize(extra_faces.size());
  for (auto kind = reader.next(vertices, faces); kind != PlyReader::ChunkKind::end;
       kind = reader.next(vertices, faces)) {
    if (kind == PlyReader::ChunkKind::vertices) {
      out.positions.insert(out.positions.end(), vertices.positions.begin(), vertices.positions.end());
      continue;
    }
    out.triangles.insert(out.triangles.end(), faces.triangles.begin(), faces.triangles.end());
    out.faces.insert(out.faces.end(), faces.faces.begin(), faces.faces.end());
    for (std::size_t k = 0; k < extra_faces.size(); ++k) {
      out.extras[k].insert(out.extras[k].end(), faces.extras[k].begin(), faces.extras[k].end());
    }
  }
  return out;
}

}  // namespace citymesh::app
