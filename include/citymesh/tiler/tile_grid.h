// SPDX-License-Identifier: MIT
// The regular grid of square tiles in the projected CRS: which tile owns a triangle (by its
// centroid) and which neighbours get a halo copy.
#pragma once

#include <array>
#include <compare>
#include <span>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "citymesh/core/vec.h"

namespace citymesh {

/// Column and row of a tile; tile (i, j) covers [origin + i*size, origin + (i+1)*size) in x
/// and likewise in y.
struct TileKey {
  std::int32_t i = 0, j = 0;
  friend constexpr auto operator<=>(const TileKey&, const TileKey&) = default;
  /// "12_-4": used in file names and messages.
  [[nodiscard]] std::string name() const;
};

struct TileGridParams {
  double tile_size = 50.0;                 ///< metres, > 0
  double halo = 2.0;                       ///< metres, 0 <= halo < tile_size / 2
  std::array<double, 2> origin{0.0, 0.0};  ///< grid origin in the project CRS
};

/// The x-y rectangle in which a box, grown by the halo, lies clearly inside one tile (see
/// TileGrid::interior).
struct TileInterior {
  TileKey key;
  double halo = 0;
  /// The tile's sides moved inwards by a rounding margin; the default rectangle holds no box
  /// that holds a point.
  double x0 = std::numeric_limits<double>::infinity(), y0 = x0, x1 = -x0, y1 = -x0;

  /// Whether the x-y extent of `box` (not empty) grown by the halo lies in the rectangle.
  [[nodiscard]] bool holds(const Box3d& box) const {
    return box.min.x - halo >= x0 && box.max.x + halo <= x1 && box.min.y - halo >= y0 && box.max.y + halo <= y1;
  }
};

class TileGrid {
 public:
  /// Throws ConfigError when the sizes are out of range.
  explicit TileGrid(const TileGridParams& params);

  [[nodiscard]] const TileGridParams& params() const { return params_; }
  /// The tile containing p (x and y only); every point has exactly one.
  [[nodiscard]] TileKey owner(const Vec3d& p) const;
  /// Lower corner of a tile in the project CRS (a natural local origin for its floats).
  [[nodiscard]] Vec3d corner(TileKey key) const;
  /// Tiles other than `owner` whose halo band (tile grown by `halo`) meets the x-y extent of
  /// `box`, in (i, j) order. A triangle is copied into these tiles as context.
  [[nodiscard]] std::vector<TileKey> halo_tiles(const Box3d& box, TileKey owner) const;
  /// Whether the x-y extent of `box` grown by the halo lies in one tile: then that tile is the
  /// only one halo_tiles, tiles_crossed and owner can name for anything inside the box.
  [[nodiscard]] bool within_one_tile(const Box3d& box) const;
  /// Every tile whose halo band (tile grown by `halo`) the x-y shadow of the convex hull of
  /// `points` truly meets (not only its bounding box), in (i, j) order. An empty-space
  /// tetrahedron (a triangle and its viewpoint) goes to these tiles, so that a conflict is
  /// found even when the sensor stood in another tile.
  [[nodiscard]] std::vector<TileKey> tiles_crossed(std::span<const Vec3d> points) const;
  /// Where a box, grown by the halo, lies inside tile `key` by more than any rounding of
  /// owner() can cross: a triangle whose corners and viewpoint lie there is owned by `key`
  /// (its centroid is inside) and copied nowhere else. The tiler keeps the last owner's, since
  /// consecutive triangles mostly fall in the same tile, and so places most triangles with
  /// four comparisons.
  [[nodiscard]] TileInterior interior(TileKey key) const;
  /// Where a triangle is copied besides its owner `owner` (the tile of its centroid):
  /// `halo` = halo_tiles(box of the corners, owner), `crossed` = tiles_crossed(corners and
  /// viewpoint) less the owner and the halo tiles, both in (i, j) order; both empty when the
  /// triangle and its viewpoint lie within the owner grown by the halo, which the tiler's
  /// triangles mostly do and which four comparisons mostly settle. Both vectors are cleared
  /// first; their room is reused from call to call.
  void copy_targets(std::span<const Vec3d, 3> corners, const Vec3d& viewpoint, TileKey owner,
                    std::vector<TileKey>& halo, std::vector<TileKey>& crossed) const;

 private:
  /// Tiles whose halo band meets the x-y extent of `box` and that `keep` accepts.
  template <class Keep>
  std::vector<TileKey> tiles_near(const Box3d& box, Keep keep) const;
  /// Whether the x-y hull of `points` meets tile `key` grown by the halo.
  [[nodiscard]] bool hull_meets_band(std::span<const Vec3d> points, TileKey key) const;
  /// The first and last column and row whose halo bands meet the x-y extent of `box`.
  struct CellRange {
    std::int32_t i0, i1, j0, j1;
    [[nodiscard]] bool holds(TileKey k) const { return k.i >= i0 && k.i <= i1 && k.j >= j0 && k.j <= j1; }
  };
  [[nodiscard]] CellRange cells_near(const Box3d& box) const;

  TileGridParams params_;
  double inverse_size_;  ///< 1 / tile_size, for owner() and cells_near()
};

}  // namespace citymesh
