// SPDX-License-Identifier: MIT
// Parts of a simulated pass, for tests that append a pass over part of a street.
#pragma once

#include <algorithm>
#include <cfloat>
#include <filesystem>
#include <string>

#include "citymesh/core/mesh.h"
#include "citymesh/io/mesh_io.h"
#include "citymesh/io/ply_writer.h"
#include "test_support.h"

namespace citymesh::test {

/// `mesh` with only the triangles whose centroid lies in the first `share` of its longer
/// horizontal extent (a pass that drove part of the street), or in the first `far_share` of it
/// on the far half of the other extent (default: the same share).
inline Mesh first_part(const Mesh& mesh, double share, double far_share = -1) {
  double lo[2] = {DBL_MAX, DBL_MAX}, hi[2] = {-DBL_MAX, -DBL_MAX};
  for (const Vec3f& p : mesh.positions) {
    lo[0] = std::min(lo[0], double(p.x)), hi[0] = std::max(hi[0], double(p.x));
    lo[1] = std::min(lo[1], double(p.y)), hi[1] = std::max(hi[1], double(p.y));
  }
  const int axis = hi[0] - lo[0] >= hi[1] - lo[1] ? 0 : 1, other = 1 - axis;
  const double middle = (lo[other] + hi[other]) / 2;
  const double end = lo[axis] + share * (hi[axis] - lo[axis]);
  const double far_end = lo[axis] + (far_share < 0 ? share : far_share) * (hi[axis] - lo[axis]);
  Mesh part = mesh;
  part.triangles.clear();
  part.triangle_ids.clear();
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    const auto [a, b, c] = mesh.corners(t);
    const Vec3d centroid = (a + b + c) / 3.0;
    const double along = axis == 0 ? centroid.x : centroid.y, across = axis == 0 ? centroid.y : centroid.x;
    if (along >= (across >= middle ? far_end : end)) continue;
    part.triangles.push_back(mesh.triangles[t]);
    part.triangle_ids.push_back(mesh.triangle_ids[t]);
  }
  return part;
}

/// In the simulated street `sim`: five.toml, its config less the last acquisition, and six.toml,
/// with the last acquisition cut by first_part(share, far_share) to acq_5_part.ply. False when
/// the config is not the simulator's six passes.
inline bool write_append_configs(const std::filesystem::path& sim, double share, double far_share = -1) {
  const std::string config = read_text(sim / "config.toml");
  const std::size_t last = config.rfind("[[acquisition]]");
  if (last == std::string::npos) return false;
  std::string sixth = config.substr(last);
  const std::size_t path = sixth.find("acq_5.ply");
  if (path == std::string::npos) return false;
  sixth.replace(path, 9, "acq_5_part.ply");
  write_text(sim / "five.toml", config.substr(0, last));
  write_text(sim / "six.toml", config.substr(0, last) + sixth);
  write_mesh_ply(sim / "acq_5_part.ply", first_part(read_mesh(sim / "acq_5.ply").mesh, share, far_share));
  return true;
}

}  // namespace citymesh::test
