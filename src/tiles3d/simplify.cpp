// SPDX-License-Identifier: MIT
// The only source that includes meshoptimizer.
#include "citymesh/tiles3d/simplify.h"

#include <meshoptimizer.h>

#include <cmath>
#include <cstring>

namespace citymesh {

SimplifiedMesh simplify_mesh(std::span<const Vec3f> positions, std::span<const Triangle> triangles,
                             const SimplifyParams& params) {
  static_assert(sizeof(Triangle) == 3 * sizeof(unsigned int) && sizeof(Vec3f) == 3 * sizeof(float));
  SimplifiedMesh out;
  if (triangles.empty()) return out;
  const std::size_t corners = triangles.size() * 3;
  const auto target = static_cast<std::size_t>(std::llround(static_cast<double>(corners) * params.target_ratio)) / 3 * 3;
  std::vector<unsigned int> kept(corners);
  float relative_error = 0.0f;
  const auto* indices = reinterpret_cast<const unsigned int*>(triangles.data());
  const auto* xyz = reinterpret_cast<const float*>(positions.data());
  const auto error = static_cast<float>(params.max_error_fraction);
  const std::size_t count =
      params.sloppy ? meshopt_simplifySloppy(kept.data(), indices, corners, xyz, positions.size(), sizeof(Vec3f),
                                             target, error, &relative_error)
                    : meshopt_simplify(kept.data(), indices, corners, xyz, positions.size(), sizeof(Vec3f), target,
                                       error, params.lock_border ? unsigned{meshopt_SimplifyLockBorder} : 0u,
                                       &relative_error);
  out.triangles.resize(count / 3);
  std::memcpy(out.triangles.data(), kept.data(), count * sizeof(unsigned int));
  const float scale = meshopt_simplifyScale(reinterpret_cast<const float*>(positions.data()), positions.size(),
                                            sizeof(Vec3f));
  out.error = static_cast<double>(relative_error) * static_cast<double>(scale);
  return out;
}

}  // namespace citymesh
