// SPDX-License-Identifier: MIT
// What the end-to-end tests check in a mosaic PLY: edges shared by more than two faces, and
// the sources its faces come from.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <map>
#include <utility>

#include "citymesh/io/ply_reader.h"

namespace citymesh::test {

/// Edges of the PLY's faces used by more than two faces, and the source_acq values seen.
inline std::pair<std::size_t, std::map<int, std::size_t>> inspect_mosaic_ply(const std::filesystem::path& ply) {
  PlyReadParams params;
  params.require_sensor_origin = false;
  params.extra_face_properties = {"source_acq", "source_face"};
  PlyReader reader(ply, params);
  PlyVertexChunk vertices;
  PlyFaceChunk faces;
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> uses;
  std::map<int, std::size_t> sources;
  for (auto kind = reader.next(vertices, faces); kind != PlyReader::ChunkKind::end; kind = reader.next(vertices, faces)) {
    if (kind != PlyReader::ChunkKind::faces) continue;
    for (std::size_t t = 0; t < faces.triangles.size(); ++t) {
      const Triangle& tri = faces.triangles[t];
      for (int k = 0; k < 3; ++k) ++uses[{std::min(tri[k], tri[(k + 1) % 3]), std::max(tri[k], tri[(k + 1) % 3])}];
      ++sources[static_cast<int>(faces.extras[0][t])];
      if (faces.extras[0][t] < 0) {
        EXPECT_EQ(faces.extras[1][t], -1.0);  // stitch triangles have no source face
      }
    }
  }
  const auto non_manifold =
      static_cast<std::size_t>(std::count_if(uses.begin(), uses.end(), [](const auto& u) { return u.second > 2; }));
  return {non_manifold, sources};
}

}  // namespace citymesh::test
