// SPDX-License-Identifier: MIT
#include "citymesh/io/ply_inspect.h"

#include <algorithm>

namespace citymesh {

PlyInspection inspect_ply(const std::filesystem::path& path, PlyReadParams params) {
  params.require_sensor_origin = false;
  PlyReader reader(path, params);
  PlyInspection result;
  result.path = path;
  result.header = reader.header();
  result.layout = reader.vertex_layout();
  PlyVertexChunk vertices;
  PlyFaceChunk faces;
  for (auto kind = reader.next(vertices, faces); kind != PlyReader::ChunkKind::end;
       kind = reader.next(vertices, faces)) {
    if (kind != PlyReader::ChunkKind::vertices) continue;
    for (const Vec3d& p : vertices.positions) result.bounds.extend(p);
    for (double t : vertices.times) {
      result.time_min = std::min(result.time_min, t);
      result.time_max = std::max(result.time_max, t);
    }
  }
  result.stats = reader.stats();
  return result;
}

}  // namespace citymesh
