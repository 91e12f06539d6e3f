// SPDX-License-Identifier: MIT
#include "citymesh/tiler/tile_grid.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "citymesh/core/error.h"

namespace citymesh {

namespace {
/// floor((coordinate - origin) / size) as an int32, the one definition of a tile's cell; throws
/// when it does not fit.
std::int32_t divided_cell(double coordinate, double origin, double size) {
  const double c = (coordinate - origin) / size;
  if (!(std::abs(c) < std::numeric_limits<std::int32_t>::max())) {
    throw InputError(fmt::format("tiling: coordinate {} is too far from the grid origin {}", coordinate, origin));
  }
  // floor() by truncation (the same value for every c in range): std::floor is a library call
  // without SSE4.1, and the tiler calls this a dozen times per triangle.
  const auto truncated = static_cast<std::int32_t>(c);
  return static_cast<double>(truncated) > c ? truncated - 1 : truncated;
}

/// divided_cell() through a multiplication by `inverse` = 1 / size: the two divisions per point
/// were a twelfth of the tiler's time. The product differs from the quotient by a few units in
/// the last place at most, so its floor is the quotient's unless it lies that close to an
/// integer; then (rarely: on tile sides) the division decides.
std::int32_t cell(double coordinate, double origin, double size, double inverse) {
  const double c = (coordinate - origin) * inverse;
  constexpr double kFastRange = 1 << 30;
  if (!(std::abs(c) < kFastRange)) return divided_cell(coordinate, origin, size);
  const auto truncated = static_cast<std::int32_t>(c);
  const std::int32_t below = static_cast<double>(truncated) > c ? truncated - 1 : truncated;
  // c's distance above its floor: exact, except for -1 < c < 0, where the sign settles it.
  const double fraction = c - below;
  const double doubt = std::abs(c) * 0x1p-48 + 0x1p-1000;
  if (fraction < doubt || fraction > 1 - doubt) return divided_cell(coordinate, origin, size);
  return below;
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

TileGrid::TileGrid(const TileGridParams& params) : params_(params), inverse_size_(1 / params.tile_size) {
  if (!(params.tile_size > 0) || !(params.halo >= 0) || params.halo * 2 >= params.tile_size) {
    throw ConfigError(fmt::format("tiling: tile_size {} must be positive and halo {} less than half of it",
                                  params.tile_size, params.halo));
  }
}

TileKey TileGrid::owner(const Vec3d& p) const {
  return {cell(p.x, params_.origin[0], params_.tile_size, inverse_size_),
          cell(p.y, params_.origin[1], params_.tile_size, inverse_size_)};
}

Vec3d TileGrid::corner(TileKey key) const {
  return {params_.origin[0] + key.i * params_.tile_size, params_.origin[1] + key.j * params_.tile_size, 0.0};
}

TileGrid::CellRange TileGrid::cells_near(const Box3d& box) const {
  const double h = params_.halo, s = params_.tile_size;
  // A tile (i, j) grown by h meets the box when [i*s - h, (i+1)*s + h] overlaps [min, max].
  const double inv = inverse_size_;
  return {cell(box.min.x - h, params_.origin[0], s, inv), cell(box.max.x + h, params_.origin[0], s, inv),
          cell(box.min.y - h, params_.origin[1], s, inv), cell(box.max.y + h, params_.origin[1], s, inv)};
}

template <class Keep>
std::vector<TileKey> TileGrid::tiles_near(const Box3d& box, Keep keep) const {
  const CellRange r = cells_near(box);
  std::vector<TileKey> tiles;
  for (std::int32_t i = r.i0; i <= r.i1; ++i) {
    for (std::int32_t j = r.j0; j <= r.j1; ++j) {
      if (keep(TileKey{i, j})) tiles.push_back({i, j});
    }
  }
  return tiles;
}

bool TileGrid::hull_meets_band(std::span<const Vec3d> points, TileKey key) const {
  const double h = params_.halo, s = params_.tile_size;
  const Vec3d c = corner(key);
  const double x0 = c.x - h, y0 = c.y - h, x1 = c.x + s + h, y1 = c.y + s + h;
  // A point inside settles it (most tiles a tetrahedron meets hold one of its corners).
  const bool holds_a_point = std::any_of(points.begin(), points.end(), [&](const Vec3d& p) {
    return p.x >= x0 && p.x <= x1 && p.y >= y0 && p.y <= y1;
  });
  return holds_a_point || hull_meets_rectangle(points, x0, y0, x1, y1);
}

std::vector<TileKey> TileGrid::halo_tiles(const Box3d& box, TileKey owner_key) const {
  return tiles_near(box, [&](TileKey k) { return k != owner_key; });
}

bool TileGrid::within_one_tile(const Box3d& box) const {
  const Vec3d grow{params_.halo, params_.halo, 0};
  return owner(box.min - grow) == owner(box.max + grow);
}

TileInterior TileGrid::interior(TileKey key) const {
  const Vec3d c = corner(key);
  const double s = params_.tile_size;
  // Far enough inside the tile's sides that no rounding of owner()'s division can put a
  // point of the grown box in another tile.
  const double margin = 1e-12 * (std::abs(c.x) + std::abs(c.y) + s) + 1e-9;
  return {key, params_.halo, c.x + margin, c.y + margin, c.x + s - margin, c.y + s - margin};
}

std::vector<TileKey> TileGrid::tiles_crossed(std::span<const Vec3d> points) const {
  Box3d box;
  for (const Vec3d& p : points) box.extend(p);
  // The shape grown by the halo inside one tile (the common case): no exact test needed.
  if (within_one_tile(box)) return {owner(box.min)};
  return tiles_near(box, [&](TileKey k) { return hull_meets_band(points, k); });
}

void TileGrid::copy_targets(std::span<const Vec3d, 3> corners, const Vec3d& viewpoint, TileKey owner_key,
                            std::vector<TileKey>& halo, std::vector<TileKey>& crossed) const {
  halo.clear();
  crossed.clear();
  Box3d box;
  for (const Vec3d& p : corners) box.extend(p);
  Box3d reach = box;
  reach.extend(viewpoint);
  if (interior(owner_key).holds(reach)) return;
  // The cells tiles_crossed would visit hold those halo_tiles would: one loop names both.
  const CellRange near_reach = cells_near(reach);
  if (near_reach.i0 == near_reach.i1 && near_reach.j0 == near_reach.j1) return;  // within one tile
  const CellRange near_box = cells_near(box);
  const std::array<Vec3d, 4> tetrahedron{corners[0], corners[1], corners[2], viewpoint};
  for (std::int32_t i = near_reach.i0; i <= near_reach.i1; ++i) {
    for (std::int32_t j = near_reach.j0; j <= near_reach.j1; ++j) {
      const TileKey k{i, j};
      if (k == owner_key) continue;
      if (near_box.holds(k)) {
        halo.push_back(k);
      } else if (hull_meets_band(tetrahedron, k)) {
        crossed.push_back(k);
      }
    }
  }
}

}  // namespace citymesh
