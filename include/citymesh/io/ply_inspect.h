// SPDX-License-Identifier: MIT
// One streaming pass over a PLY file that validates it and summarises what it holds.
#pragma once

#include <filesystem>
#include <limits>

#include "citymesh/core/vec.h"
#include "citymesh/io/ply_reader.h"

namespace citymesh {

struct PlyInspection {
  std::filesystem::path path;
  PlyHeader header;
  PlyVertexLayout layout;
  PlyReadStats stats;
  Box3d bounds;  ///< absolute positions (header offset applied)
  double time_min = std::numeric_limits<double>::infinity();
  double time_max = -std::numeric_limits<double>::infinity();
};

/// Reads the whole file in bounded chunks. Sensor positions are reported, not required.
/// Throws InputError on any malformed content.
PlyInspection inspect_ply(const std::filesystem::path& path, PlyReadParams params = {});

}  // namespace citymesh
