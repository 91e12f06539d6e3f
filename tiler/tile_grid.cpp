// SPDX-License-Identifier: MIT
#include "citymesh/tiler/tile_grid.h"

#include <fmt/format.h>

#include <cmath>
#include <limits>

#include "citymesh/core/error.h"

namespace citymesh {

namespace {
std::int32_t cell(double coordinate, double origin, double size) {
  const double c = std::floor((coordinate - origin) / size);
  if (!(std::abs(c) < std::numeric_limits<std::int32_t>::max())) {
    throw InputError(fmt::format("tiling: coordinate {} is too far from the grid origin {}", coordinate, origin));
  }
  return static_cast<std::int32_t>(c);
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

std::vector<TileKey> TileGrid::halo_tiles(const Box3d& box, TileKey owner_key) const {
  const double h = params_.halo, s = params_.tile_size;
  // A tile (i, j) grown by h meets the box when [i*s - h, (i+1)*s + h] overlaps [min, max].
  const std::int32_t i0 = cell(box.min.x - h, params_.origin[0], s), i1 = cell(box.max.x + h, params_.origin[0], s);
  const std::int32_t j0 = cell(box.min.y - h, params_.origin[1], s), j1 = cell(box.max.y + h, params_.origin[1], s);
  std::vector<TileKey> tiles;
  for (std::int32_t i = i0; i <= i1; ++i) {
    for (std::int32_t j = j0; j <= j1; ++j) {
      if (TileKey{i, j} != owner_key) tiles.push_back({i, j});
    }
  }
  return tiles;
}

}  // namespace citymesh
