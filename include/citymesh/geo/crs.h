// SPDX-License-Identifier: MIT
// Projected and local coordinate reference systems, to and from geodetic and ECEF
// (GeographicLib behind this header).
#pragma once

#include <array>
#include <memory>
#include <string>
#include <string_view>

#include "citymesh/core/vec.h"

namespace citymesh {

/// What the third coordinate of the project CRS means. Never assumed: a conversion that needs
/// an ellipsoidal height throws ConfigError while the datum is `unset`.
struct VerticalDatum {
  enum class Kind { unset, ellipsoidal, orthometric };
  Kind kind = Kind::unset;
  /// Geoid undulation N in metres (ellipsoidal height = orthometric height + N); orthometric only.
  double geoid_undulation = 0.0;
};

/// Latitude and longitude in degrees, height above the ellipsoid in metres.
struct Geodetic {
  double lat = 0, lon = 0, height = 0;
};

/// Where a CRS is meant for, in degrees: EPSG's area of use widened by a margin, so that data
/// near its edges passes. A point outside it lies in another CRS's coordinates (longitude and
/// latitude given as metres, another projection, another UTM zone or hemisphere).
struct AreaOfUse {
  double lat_min = -90, lat_max = 90, lon_min = -180, lon_max = 180;
  /// False for NaN coordinates too.
  [[nodiscard]] bool holds(const Geodetic& g) const {
    return g.lat >= lat_min && g.lat <= lat_max && g.lon >= lon_min && g.lon <= lon_max;
  }
};

/// A project coordinate reference system:
/// - "EPSG:2154": RGF93 / Lambert-93 (GRS80);
/// - "EPSG:32601".."EPSG:32660" and "EPSG:32701".."EPSG:32760": WGS 84 / UTM north and south;
/// - "ENU:lat,lon,h": a local east-north-up frame (metres) whose origin is the WGS 84 point
///   (lat, lon in degrees; h in the configured vertical datum).
/// RGF93 is taken as coincident with WGS 84 (they differ by well under a metre), which is what
/// web globes expect. Copyable and cheap to pass by value.
class Crs {
 public:
  /// Throws ConfigError naming `spec` when it is not one of the forms above.
  static Crs parse(std::string_view spec, VerticalDatum datum = {});

  [[nodiscard]] const std::string& spec() const;
  /// Human-readable name, e.g. "RGF93 / Lambert-93".
  [[nodiscard]] std::string name() const;
  [[nodiscard]] const VerticalDatum& vertical_datum() const;
  [[nodiscard]] bool is_local_frame() const;
  /// Lambert-93: metropolitan France and Corsica (EPSG: 41.15..51.56 N, 9.86 W..10.38 E) and a
  /// degree around; UTM: the zone's 6-degree band and 1.5 degrees either side (any longitude
  /// for zones 1 and 60, whose margin crosses the antimeridian), its hemisphere and a degree
  /// across the equator; a local ENU frame: a degree around its origin.
  [[nodiscard]] AreaOfUse area_of_use() const;

  /// Latitude/longitude of a projected point (the height is irrelevant, no datum needed).
  [[nodiscard]] Geodetic to_lat_lon(const Vec3d& p) const;
  /// Full geodetic position; requires a vertical datum.
  [[nodiscard]] Geodetic to_geodetic(const Vec3d& p) const;
  [[nodiscard]] Vec3d from_geodetic(const Geodetic& g) const;
  /// Earth-centred, earth-fixed coordinates (metres); requires a vertical datum.
  [[nodiscard]] Vec3d to_ecef(const Vec3d& p) const;
  [[nodiscard]] Vec3d from_ecef(const Vec3d& ecef) const;

  struct Impl;

 private:
  explicit Crs(std::shared_ptr<const Impl> impl) : impl_(std::move(impl)) {}
  std::shared_ptr<const Impl> impl_;
};

/// A local east-north-up frame tangent to the WGS 84 ellipsoid at a point (the frame of 3D
/// Tiles content): conversions to and from ECEF as doubles.
class EnuFrame {
 public:
  explicit EnuFrame(const Geodetic& origin);
  [[nodiscard]] Vec3d to_ecef(const Vec3d& enu) const;
  [[nodiscard]] Vec3d from_ecef(const Vec3d& ecef) const;
  /// The 4x4 ENU -> ECEF transform, column-major (a 3D Tiles `transform`).
  [[nodiscard]] std::array<double, 16> to_ecef_matrix() const;
  [[nodiscard]] const Geodetic& origin() const { return origin_; }

 private:
  Geodetic origin_;
  Vec3d origin_ecef_;
  std::array<double, 9> rotation_{};  ///< row-major; ECEF = rotation * ENU + origin
};

/// Parses "ellipsoidal" or "orthometric" (with its undulation); throws ConfigError otherwise.
VerticalDatum parse_vertical_datum(std::string_view kind, double geoid_undulation);

}  // namespace citymesh
