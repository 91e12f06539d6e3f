// SPDX-License-Identifier: MIT
// The regular grid of square tiles in the projected CRS: which tile owns a triangle (by its
// centroid) and which neighbours get a halo copy.
#pragma once

#include <array>
#include <compare>
#include <span>
#include <cstdint>
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

 private:
  /// Tiles whose halo band meets the x-y extent of `box` and that `keep` accepts.
  template <class Keep>
  std::vector<TileKey> tiles_near(const Box3d& box, Keep keep) const;

  TileGridParams params_;
};

}  // namespace citymesh
