// SPDX-License-Identifier: MIT
#include "citymesh/tiler/tile_grid.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "citymesh/core/error.h"

namespace citymesh {

namespace {
std::int32_t cell(double coordinate, double origin, double size) {
  const double c = (coordinate - origin) / size;
  if (!(std::abs(c) < std::numeric_limits<std::int32_t>::max())) {
    throw InputError(fmt::format("tiling: coordinate {} is too far from the grid origin {}", coordinate, origin));
  }
  // floor() by truncation (the same value for every c in range): std::floor is a library call
  // without SSE4.1, and the tiler calls this a dozen times per triangle.
  const auto truncated = static_cast<std::int32_t>(c);
  return static_cast<double>(truncated) > c ? truncated - 1 : truncated;
}
/// Whether the x-y convex hull of `points` meets the rectangle [lo, hi], by separating axes:
/// the rectangle's two axes and the normal of every segment between two points (the hull's
/// edges are among them; an extra axis can only find a true separation).
bool hull_meets_rectangle(std::span<const Vec3d> points, double lo_x, double lo_y, double hi_x, double hi_y) {
  const auto separated = [&](double nx, double ny) {
    double pmin = std::numeric_limits<double>::infinity(), pmax = -pmin;
    for (const Vec3d& p : points) {
      pmin = std::min(pmin, nx * p.x + ny * p.y);
      pmax = std::max(pmax, nx * p.x + ny * p.y);
    }
    const double c0 = nx * lo_x + ny * lo_y, c1 = nx * hi_x + ny * lo_y, c2 = nx * lo_x + ny * hi_y,
                 c3 = nx * hi_x + ny * hi_y;
    return pmax < std::min({c0, c1, c2, c3}) || pmin > std::max({c0, c1, c2, c3});
  };
  if (separated(1, 0) || separated(0, 1)) return false;
  for (std::size_t a = 0; a < points.size(); ++a) {
    for (std::size_t b = a + 1; b < points.size(); ++b) {
      const double nx = points[b].y - points[a].y, ny = points[a].x - points[b].x;
      if ((nx != 0 || ny != 0) && separated(nx, ny)) return false;
    }
  }
  return true;
}

}  // namespace

std::string TileKey::name() const { return fmt::format("{}_{}", i, j); }

TileGrid::TileGrid(const TileGridParams& params) : params_(params) {
  if (!(params.tile_size > 0) || !(params.halo >= 0) || params.halo * 2 >= params.tile_size) {
    throw ConfigError(fmt::format("tiling: tile_size {} must be positive and halo {} less than half of it",
                                  params.tile_size, params.halo));
  }
}

TileKey TileGrid::owner(const Vec3d& p) const {
  return {cell(p.x, params_.origin[0], params_.tile_size), cell(p.y, params_.origin[1], params_.tile_size)};
}

Vec3d TileGrid::corner(TileKey key) const {
  return {params_.origin[0] + key.i * params_.tile_size, params_.origin[1] + key.j * params_.tile_size, 0.0};
}

template <class Keep>
std::vector<TileKey> TileGrid::tiles_near(const Box3d& box, Keep keep) const {
  const double h = params_.halo, s = params_.tile_size;
  // A tile (i, j) grown by h meets the box when [i*s - h, (i+1)*s + h] overlaps [min, max].
  const std::int32_t i0 = cell(box.min.x - h, params_.origin[0], s), i1 = cell(box.max.x + h, params_.origin[0], s);
  const std::int32_t j0 = cell(box.min.y - h, params_.origin[1], s), j1 = cell(box.max.y + h, params_.origin[1], s);
  std::vector<TileKey> tiles;
  for (std::int32_t i = i0; i <= i1; ++i) {
    for (std::int32_t j = j0; j <= j1; ++j) {
      if (keep(TileKey{i, j})) tiles.push_back({i, j});
    }
  }
  return tiles;
}

std::vector<TileKey> TileGrid::halo_tiles(const Box3d& box, TileKey owner_key) const {
  return tiles_near(box, [&](TileKey k) { return k != owner_key; });
}

bool TileGrid::within_one_tile(const Box3d& box) const {
  const Vec3d grow{params_.halo, params_.halo, 0};
  return owner(box.min - grow) == owner(box.max + grow);
}

std::vector<TileKey> TileGrid::tiles_crossed(std::span<const Vec3d> points) const {
  Box3d box;
  for (const Vec3d& p : points) box.extend(p);
  const double h = params_.halo, s = params_.tile_size;
  // The shape grown by the halo inside one tile (the common case): no exact test needed.
  if (within_one_tile(box)) return {owner(box.min)};
  return tiles_near(box, [&](TileKey k) {
    const Vec3d c = corner(k);
    const double x0 = c.x - h, y0 = c.y - h, x1 = c.x + s + h, y1 = c.y + s + h;
    // A point inside settles it (most tiles a tetrahedron meets hold one of its corners).
    const bool holds_a_point = std::any_of(points.begin(), points.end(), [&](const Vec3d& p) {
      return p.x >= x0 && p.x <= x1 && p.y >= y0 && p.y <= y1;
    });
    return holds_a_point || hull_meets_rectangle(points, x0, y0, x1, y1);
  });
}

}  // namespace citymesh
