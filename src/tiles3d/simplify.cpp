// SPDX-License-Identifier: MIT
// The only source that includes meshoptimizer.
#include "citymesh/tiles3d/simplify.h"

#include <fmt/format.h>
#include <meshoptimizer.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numeric>
#include <vector>

#include "citymesh/core/checksum.h"
#include "citymesh/core/error.h"

namespace citymesh {

namespace {

/// `positions` followed by two more copies of each locked one. meshoptimizer 0.18 has no
/// per-vertex lock, but it never moves a position shared by more than two vertices (it cannot
/// tell how their attributes join): copies that no triangle uses lock a vertex and change
/// nothing else (later releases take per-vertex locks; Debian 12 ships 0.18).
std::vector<Vec3f> with_lock_copies(std::span<const Vec3f> positions, std::span<const std::uint8_t> locked) {
  std::vector<Vec3f> out(positions.begin(), positions.end());
  for (std::size_t v = 0; v < locked.size(); ++v) {
    if (locked[v] != 0) out.insert(out.end(), 2, positions[v]);
  }
  return out;
}

/// A mesh on one vertex per position: `first` is the input vertex each came from (the first
/// with its position), `triangles` the input's on them less those that lost a corner, and a
/// position is locked when any of its input vertices is.
struct Welded {
  std::vector<Vec3f> positions;
  std::vector<std::uint32_t> first;
  std::vector<Triangle> triangles;
  std::vector<std::uint8_t> locked;
};

Welded weld(std::span<const Vec3f> positions, std::span<const Triangle> triangles,
            std::span<const std::uint8_t> locked) {
  const auto bits = [&](std::uint32_t v) { return position_bits(positions[v]); };
  std::vector<std::uint32_t> order(positions.size());
  std::iota(order.begin(), order.end(), 0u);
  std::stable_sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) { return bits(a) < bits(b); });
  Welded w;
  std::vector<std::uint32_t> index(positions.size());
  for (std::size_t k = 0; k < order.size(); ++k) {
    const std::uint32_t v = order[k];
    if (k == 0 || bits(v) != bits(order[k - 1])) {
      w.positions.push_back(positions[v]);
      w.first.push_back(v);  // the smallest index of its position: the sort is stable
      w.locked.push_back(0);
    }
    index[v] = static_cast<std::uint32_t>(w.positions.size() - 1);
    if (!locked.empty() && locked[v] != 0) w.locked.back() = 1;
  }
  for (const Triangle& t : triangles) {
    const Triangle u{index[t[0]], index[t[1]], index[t[2]]};
    if (u[0] != u[1] && u[1] != u[2] && u[0] != u[2]) w.triangles.push_back(u);
  }
  return w;
}

SimplifiedMesh simplify_unwelded(std::span<const Vec3f> positions, std::span<const Triangle> triangles,
                                 const SimplifyParams& params, std::span<const std::uint8_t> locked) {
  SimplifiedMesh out;
  if (triangles.empty()) return out;
  const std::size_t corners = triangles.size() * 3;
  const auto target =
      static_cast<std::size_t>(std::llround(static_cast<double>(corners) * params.target_ratio)) / 3 * 3;
  std::vector<unsigned int> kept(corners);
  float relative_error = 0.0f;
  const std::vector<Vec3f> copies =
      params.sloppy || locked.empty() ? std::vector<Vec3f>{} : with_lock_copies(positions, locked);
  const std::span<const Vec3f> all = copies.empty() ? positions : std::span<const Vec3f>(copies);
  const auto* indices = reinterpret_cast<const unsigned int*>(triangles.data());
  const auto* xyz = reinterpret_cast<const float*>(all.data());
  const auto error = static_cast<float>(params.max_error_fraction);
  const std::size_t count =
      params.sloppy ? meshopt_simplifySloppy(kept.data(), indices, corners, xyz, positions.size(), sizeof(Vec3f),
                                             target, error, &relative_error)
                    : meshopt_simplify(kept.data(), indices, corners, xyz, all.size(), sizeof(Vec3f), target, error,
                                       params.lock_border ? unsigned{meshopt_SimplifyLockBorder} : 0u, &relative_error);
  out.triangles.resize(count / 3);
  std::memcpy(out.triangles.data(), kept.data(), count * sizeof(unsigned int));
  const float scale =
      meshopt_simplifyScale(reinterpret_cast<const float*>(positions.data()), positions.size(), sizeof(Vec3f));
  out.error = static_cast<double>(relative_error) * static_cast<double>(scale);
  return out;
}

}  // namespace

SimplifiedMesh simplify_mesh(std::span<const Vec3f> positions, std::span<const Triangle> triangles,
                             const SimplifyParams& params, std::span<const std::uint8_t> locked) {
  static_assert(sizeof(Triangle) == 3 * sizeof(unsigned int) && sizeof(Vec3f) == 3 * sizeof(float));
  if (!locked.empty() && locked.size() != positions.size()) {
    throw ProcessingError(fmt::format("simplify: {} lock flags for {} vertices", locked.size(), positions.size()));
  }
  if (!params.weld) return simplify_unwelded(positions, triangles, params, locked);
  const Welded w = weld(positions, triangles, locked);
  SimplifiedMesh out = simplify_unwelded(w.positions, w.triangles, params, w.locked);
  for (Triangle& t : out.triangles) t = {w.first[t[0]], w.first[t[1]], w.first[t[2]]};
  return out;
}

std::uint64_t simplify_digest(std::span<const Vec3f> positions, std::span<const Triangle> triangles,
                              const SimplifyParams& params, std::span<const std::uint8_t> locked) {
  constexpr std::uint64_t kFormat = 1;  // bumped when simplify_mesh changes what it makes
  BulkChecksum sum;
  sum.add_value(kFormat);
  sum.add_value(std::int64_t{MESHOPTIMIZER_VERSION});
  sum.add_array(positions);
  sum.add_array(triangles);
  // Field by field: the struct's padding would make equal parameters digest differently.
  sum.add_value(params.target_ratio);
  sum.add_value(params.max_error_fraction);
  sum.add_value(params.lock_border);
  sum.add_value(params.sloppy);
  sum.add_value(params.weld);
  sum.add_array(locked);
  return sum.value();
}

SimplifiedMesh simplify_mesh_kept(SimplifyCache* cache, std::span<const Vec3f> positions,
                                  std::span<const Triangle> triangles, const SimplifyParams& params,
                                  std::span<const std::uint8_t> locked) {
  if (cache == nullptr) return simplify_mesh(positions, triangles, params, locked);
  const std::uint64_t digest = simplify_digest(positions, triangles, params, locked);
  if (std::optional<SimplifiedMesh> found = cache->find(digest)) {
    const auto fits = [&](const Triangle& t) {
      return t[0] < positions.size() && t[1] < positions.size() && t[2] < positions.size();
    };
    if (std::all_of(found->triangles.begin(), found->triangles.end(), fits)) return std::move(*found);
  }
  SimplifiedMesh out = simplify_mesh(positions, triangles, params, locked);
  cache->keep(digest, out);
  return out;
}

}  // namespace citymesh
