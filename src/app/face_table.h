// SPDX-License-Identifier: MIT
// A PLY read whole with some per-face properties, for the evaluation (which needs faces as
// the file has them, with no triangle dropped).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "citymesh/core/geometry.h"
#include "citymesh/core/mesh.h"

namespace citymesh::app {

struct FaceTable {
  std::vector<Vec3d> positions;  ///< absolute
  std::vector<Triangle> triangles;
  std::vector<std::uint64_t> faces;         ///< face row of each triangle in the file
  std::vector<std::vector<double>> extras;  ///< one column per requested property

  /// The triangles in a Mesh with floats relative to `origin`.
  [[nodiscard]] Mesh local_mesh(const Vec3d& origin) const;
  [[nodiscard]] TriangleCorners corners(std::size_t t) const;
};

/// Reads `path`; every name in `extra_faces` must be a face property. Throws InputError.
FaceTable read_face_table(const std::filesystem::path& path, const std::vector<std::string>& extra_faces);

}  // namespace citymesh::app
