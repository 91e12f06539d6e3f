// SPDX-License-Identifier: MIT
#include "citymesh/geo/local_frame_map.h"

#include <array>
#include <cmath>
#include <cstdint>
#include <unordered_map>

namespace citymesh {
namespace {

/// A cube of the lattice: its index along each axis.
struct CubeKey {
  std::int64_t x = 0, y = 0, z = 0;
  bool operator==(const CubeKey&) const = default;
};

struct CubeKeyHash {
  std::size_t operator()(const CubeKey& k) const {
    const auto mix = [](std::uint64_t h, std::int64_t v) {
      return (h ^ static_cast<std::uint64_t>(v)) * 0x9E3779B97F4A7C15ull;
    };
    return static_cast<std::size_t>(mix(mix(mix(0, k.x), k.y), k.z));
  }
};

/// One cube's interpolant: the exact local positions at its 3x3x3 nodes, as offsets from the
/// centre node's (small numbers keep the weighted sum's rounding far below the float step).
struct Cube {
  Vec3d min;
  Vec3d centre;
  std::array<Vec3d, 27> offsets{};
  bool exact = false;  ///< the interpolant failed its check: map exactly
};

Vec3d exact_local(const Crs& crs, const EnuFrame& frame, const Vec3d& p) { return frame.from_ecef(crs.to_ecef(p)); }

/// The quadratic Lagrange weights of nodes 0, 1/2 and 1 at u.
std::array<double, 3> quadratic_weights(double u) {
  return {2.0 * (u - 0.5) * (u - 1.0), -4.0 * u * (u - 1.0), 2.0 * u * (u - 0.5)};
}

/// The interpolant at `u` (the position within the cube, 0..1 on each axis). The sum runs in
/// one fixed order, so equal inputs give equal bits.
Vec3d interpolate(const Cube& cube, const Vec3d& u) {
  const std::array<double, 3> wx = quadratic_weights(u.x), wy = quadratic_weights(u.y), wz = quadratic_weights(u.z);
  Vec3d sum{0, 0, 0};
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      const double wij = wx[i] * wy[j];
      for (int k = 0; k < 3; ++k) sum = sum + cube.offsets[(i * 3 + j) * 3 + k] * (wij * wz[k]);
    }
  }
  return cube.centre + sum;
}

Cube make_cube(const CubeKey& key, const Crs& crs, const EnuFrame& frame, const LocalFrameMapParams& params) {
  Cube cube;
  const double c = params.cell;
  cube.min = {double(key.x) * c, double(key.y) * c, double(key.z) * c};
  const auto at = [&](double u, double v, double w) { return cube.min + Vec3d{u * c, v * c, w * c}; };
  cube.centre = exact_local(crs, frame, at(0.5, 0.5, 0.5));
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      for (int k = 0; k < 3; ++k) {
        cube.offsets[(i * 3 + j) * 3 + k] = exact_local(crs, frame, at(0.5 * i, 0.5 * j, 0.5 * k)) - cube.centre;
      }
    }
  }
  // A quadratic interpolant strays most near a quarter of the way from a node: checked there.
  for (const double u : {0.25, 0.75}) {
    for (const double v : {0.25, 0.75}) {
      for (const double w : {0.25, 0.75}) {
        const Vec3d error = interpolate(cube, {u, v, w}) - exact_local(crs, frame, at(u, v, w));
        if (!(norm(error) <= params.tolerance)) cube.exact = true;
      }
    }
  }
  return cube;
}

/// The cubes one call has built, found by key (the last one found first: neighbouring
/// positions mostly share a cube).
class CubeCache {
 public:
  CubeCache(const Crs& crs, const EnuFrame& frame, const LocalFrameMapParams& params)
      : crs_(crs), frame_(frame), params_(params) {}

  const Cube& of(const CubeKey& key) {
    if (last_ != nullptr && last_key_ == key) return *last_;
    auto found = cubes_.find(key);
    if (found == cubes_.end()) found = cubes_.emplace(key, make_cube(key, crs_, frame_, params_)).first;
    last_key_ = key;
    last_ = &found->second;  // unordered_map keeps its elements where they are
    return *last_;
  }

 private:
  const Crs& crs_;
  const EnuFrame& frame_;
  const LocalFrameMapParams& params_;
  std::unordered_map<CubeKey, Cube, CubeKeyHash> cubes_;
  CubeKey last_key_;
  const Cube* last_ = nullptr;
};

/// Positions past this many cells from the CRS's origin are mapped exactly (no cube index
/// would hold them).
constexpr double kMaxCells = 1e15;

}  // namespace

Vec3f exact_local_position(const Crs& crs, const EnuFrame& frame, const Vec3d& p) {
  return Vec3f(exact_local(crs, frame, p));
}

std::vector<Vec3f> map_to_local_frame(std::span<const Vec3d> positions, const Crs& crs, const EnuFrame& frame,
                                      const LocalFrameMapParams& params) {
  std::vector<Vec3f> out;
  out.reserve(positions.size());
  CubeCache cubes(crs, frame, params);
  for (const Vec3d& p : positions) {
    const Vec3d cells = p / params.cell;
    if (!(std::abs(cells.x) < kMaxCells && std::abs(cells.y) < kMaxCells && std::abs(cells.z) < kMaxCells)) {
      out.push_back(exact_local_position(crs, frame, p));
      continue;
    }
    const CubeKey key{std::int64_t(std::floor(cells.x)), std::int64_t(std::floor(cells.y)),
                      std::int64_t(std::floor(cells.z))};
    const Cube& cube = cubes.of(key);
    out.push_back(cube.exact ? exact_local_position(crs, frame, p)
                             : Vec3f(interpolate(cube, (p - cube.min) / params.cell)));
  }
  return out;
}

}  // namespace citymesh
