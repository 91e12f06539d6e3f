// SPDX-License-Identifier: MIT
// The only source that includes GeographicLib.
#include "citymesh/geo/crs.h"

#include <GeographicLib/Constants.hpp>
#include <GeographicLib/Geocentric.hpp>
#include <GeographicLib/LambertConformalConic.hpp>
#include <GeographicLib/LocalCartesian.hpp>
#include <GeographicLib/TransverseMercator.hpp>
#include <fmt/format.h>

#include <charconv>
#include <cmath>
#include <optional>
#include <variant>
#include <vector>

#include "citymesh/core/error.h"

namespace citymesh {

namespace {

namespace gl = GeographicLib;

constexpr const char* kForms =
    "expected EPSG:2154, EPSG:32601..32660, EPSG:32701..32760 or ENU:lat,lon,h";

/// RGF93 / Lambert-93 on GRS80: secant conic, standard parallels 44° and 49°, false origin
/// (3°E, 46.5°N) at (700 000, 6 600 000).
struct Lambert93 {
  static constexpr double kLon0 = 3.0, kLat0 = 46.5, kFalseEasting = 700000.0,
                          kFalseNorthing = 6600000.0;
  gl::LambertConformalConic lcc{gl::Constants::WGS84_a(), 1 / 298.257222101, 44.0, 49.0, 1.0};
  double y_at_lat0 = 0;  // GeographicLib measures y from its own origin latitude

  Lambert93() {
    double x = 0, gamma = 0, k = 0;
    lcc.Forward(kLon0, kLat0, kLon0, x, y_at_lat0, gamma, k);
  }
  void forward(double lat, double lon, double& x, double& y) const {
    double gamma = 0, k = 0;
    lcc.Forward(kLon0, lat, lon, x, y, gamma, k);
    x += kFalseEasting;
    y += kFalseNorthing - y_at_lat0;
  }
  void reverse(double x, double y, double& lat, double& lon) const {
    double gamma = 0, k = 0;
    lcc.Reverse(kLon0, x - kFalseEasting, y - kFalseNorthing + y_at_lat0, lat, lon, gamma, k);
  }
};

/// WGS 84 / UTM zone `zone`, northern or southern hemisphere false northing.
struct Utm {
  int zone = 31;
  bool north = true;
  void forward(double lat, double lon, double& x, double& y) const {
    double gamma = 0, k = 0;
    gl::TransverseMercator::UTM().Forward(central_meridian(), lat, lon, x, y, gamma, k);
    x += 500000.0;
    if (!north) y += 10000000.0;
  }
  void reverse(double x, double y, double& lat, double& lon) const {
    double gamma = 0, k = 0;
    gl::TransverseMercator::UTM().Reverse(central_meridian(), x - 500000.0,
                                          north ? y : y - 10000000.0, lat, lon, gamma, k);
  }
  [[nodiscard]] double central_meridian() const { return zone * 6.0 - 183.0; }
};

struct LocalEnu {
  double lat0 = 0, lon0 = 0, h0 = 0;  // h0 as written, in the configured vertical datum
};

std::optional<std::vector<double>> parse_numbers(std::string_view text) {
  std::vector<double> values;
  while (true) {
    double v = 0;
    auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
    if (ec != std::errc() || !std::isfinite(v)) return std::nullopt;
    values.push_back(v);
    text.remove_prefix(static_cast<std::size_t>(end - text.data()));
    if (text.empty()) return values;
    if (text.front() != ',') return std::nullopt;
    text.remove_prefix(1);
  }
}

}  // namespace

struct Crs::Impl {
  std::string spec;
  VerticalDatum datum;
  std::variant<Lambert93, Utm, LocalEnu> projection;
  std::optional<gl::LocalCartesian> enu;  // set for LocalEnu

  [[nodiscard]] double ellipsoidal_offset() const {
    if (datum.kind == VerticalDatum::Kind::unset) {
      throw ConfigError(fmt::format(
          "crs {}: heights need an explicit vertical datum: set [project] vertical_datum to "
          "\"ellipsoidal\" or \"orthometric\" (with geoid_undulation)",
          spec));
    }
    return datum.kind == VerticalDatum::Kind::orthometric ? datum.geoid_undulation : 0.0;
  }
};

AreaOfUse Crs::area_of_use() const {
  if (std::holds_alternative<Lambert93>(impl_->projection)) return {40.15, 52.56, -10.86, 11.38};
  if (const auto* utm = std::get_if<Utm>(&impl_->projection)) {
    AreaOfUse area =
        utm->north ? AreaOfUse{.lat_min = -1.0, .lat_max = 85.0} : AreaOfUse{.lat_min = -81.0, .lat_max = 1.0};
    const double lon0 = utm->central_meridian();
    // Zones 1 and 60 reach across the antimeridian: their longitudes are not one interval.
    if (std::abs(lon0) + 4.5 <= 180.0) {
      area.lon_min = lon0 - 4.5;
      area.lon_max = lon0 + 4.5;
    }
    return area;
  }
  const auto& enu = std::get<LocalEnu>(impl_->projection);
  // Near a pole or the antimeridian a box of degrees does not hold the frame's surroundings.
  if (std::abs(enu.lat0) > 88.0 || std::abs(enu.lon0) > 178.0) return {};
  return {enu.lat0 - 1.0, enu.lat0 + 1.0, enu.lon0 - 1.0, enu.lon0 + 1.0};
}

Crs Crs::parse(std::string_view spec, VerticalDatum datum) {
  auto impl = std::make_shared<Impl>();
  impl->spec = std::string(spec);
  impl->datum = datum;
  auto bad = [&](std::string_view why) {
    return ConfigError(fmt::format("crs '{}': {}", spec, why));
  };
  if (spec.starts_with("EPSG:")) {
    int code = 0;
    std::string_view digits = spec.substr(5);
    auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), code);
    if (ec != std::errc() || end != digits.data() + digits.size()) throw bad(kForms);
    if (code == 2154) {
      impl->projection = Lambert93{};
    } else if ((code > 32600 && code <= 32660) || (code > 32700 && code <= 32760)) {
      impl->projection = Utm{code % 100, code < 32700};
    } else {
      throw bad(fmt::format("EPSG:{} is not supported ({})", code, kForms));
    }
  } else if (spec.starts_with("ENU:")) {
    auto numbers = parse_numbers(spec.substr(4));
    if (!numbers || numbers->size() != 3) throw bad("ENU needs three numbers: ENU:lat,lon,h");
    const double lat = (*numbers)[0], lon = (*numbers)[1], h = (*numbers)[2];
    if (std::abs(lat) > 90 || std::abs(lon) > 180) throw bad("latitude or longitude out of range");
    impl->projection = LocalEnu{lat, lon, h};
    const double h_ellipsoidal = datum.kind == VerticalDatum::Kind::orthometric ? h + datum.geoid_undulation : h;
    impl->enu.emplace(lat, lon, h_ellipsoidal, gl::Geocentric::WGS84());
  } else {
    throw bad(kForms);
  }
  return Crs(std::move(impl));
}

const std::string& Crs::spec() const { return impl_->spec; }
const VerticalDatum& Crs::vertical_datum() const { return impl_->datum; }
bool Crs::is_local_frame() const { return std::holds_alternative<LocalEnu>(impl_->projection); }

std::string Crs::name() const {
  if (std::holds_alternative<Lambert93>(impl_->projection)) return "RGF93 / Lambert-93";
  if (const auto* utm = std::get_if<Utm>(&impl_->projection)) {
    return fmt::format("WGS 84 / UTM zone {}{}", utm->zone, utm->north ? 'N' : 'S');
  }
  const auto& enu = std::get<LocalEnu>(impl_->projection);
  return fmt::format("local ENU frame at {}, {}, {}", enu.lat0, enu.lon0, enu.h0);
}

Geodetic Crs::to_lat_lon(const Vec3d& p) const {
  Geodetic g;
  if (impl_->enu) {
    impl_->enu->Reverse(p.x, p.y, p.z, g.lat, g.lon, g.height);
    return g;
  }
  std::visit(
      [&](const auto& proj) {
        if constexpr (!std::is_same_v<std::decay_t<decltype(proj)>, LocalEnu>) {
          proj.reverse(p.x, p.y, g.lat, g.lon);
        }
      },
      impl_->projection);
  g.height = p.z;
  return g;
}

Geodetic Crs::to_geodetic(const Vec3d& p) const {
  const double offset = impl_->ellipsoidal_offset();
  Geodetic g = to_lat_lon(p);
  if (!impl_->enu) g.height = p.z + offset;  // the ENU frame already holds its datum
  return g;
}

Vec3d Crs::from_geodetic(const Geodetic& g) const {
  const double offset = impl_->ellipsoidal_offset();
  Vec3d p;
  if (impl_->enu) {
    impl_->enu->Forward(g.lat, g.lon, g.height, p.x, p.y, p.z);
    return p;
  }
  std::visit(
      [&](const auto& proj) {
        if constexpr (!std::is_same_v<std::decay_t<decltype(proj)>, LocalEnu>) {
          proj.forward(g.lat, g.lon, p.x, p.y);
        }
      },
      impl_->projection);
  p.z = g.height - offset;
  return p;
}

Vec3d Crs::to_ecef(const Vec3d& p) const {
  const Geodetic g = to_geodetic(p);
  Vec3d e;
  gl::Geocentric::WGS84().Forward(g.lat, g.lon, g.height, e.x, e.y, e.z);
  return e;
}

Vec3d Crs::from_ecef(const Vec3d& ecef) const {
  Geodetic g;
  gl::Geocentric::WGS84().Reverse(ecef.x, ecef.y, ecef.z, g.lat, g.lon, g.height);
  return from_geodetic(g);
}

EnuFrame::EnuFrame(const Geodetic& origin) : origin_(origin) {
  std::vector<double> m(9);
  gl::Geocentric::WGS84().Forward(origin.lat, origin.lon, origin.height, origin_ecef_.x, origin_ecef_.y,
                                  origin_ecef_.z, m);
  std::copy(m.begin(), m.end(), rotation_.begin());
}

Vec3d EnuFrame::to_ecef(const Vec3d& enu) const {
  const auto& r = rotation_;
  return {origin_ecef_.x + r[0] * enu.x + r[1] * enu.y + r[2] * enu.z,
          origin_ecef_.y + r[3] * enu.x + r[4] * enu.y + r[5] * enu.z,
          origin_ecef_.z + r[6] * enu.x + r[7] * enu.y + r[8] * enu.z};
}

Vec3d EnuFrame::from_ecef(const Vec3d& ecef) const {
  const auto& r = rotation_;
  const Vec3d d = ecef - origin_ecef_;
  return {r[0] * d.x + r[3] * d.y + r[6] * d.z, r[1] * d.x + r[4] * d.y + r[7] * d.z,
          r[2] * d.x + r[5] * d.y + r[8] * d.z};
}

std::array<double, 16> EnuFrame::to_ecef_matrix() const {
  const auto& r = rotation_;
  return {r[0], r[3], r[6], 0, r[1], r[4], r[7], 0, r[2], r[5], r[8], 0,
          origin_ecef_.x, origin_ecef_.y, origin_ecef_.z, 1};
}

VerticalDatum parse_vertical_datum(std::string_view kind, double geoid_undulation) {
  if (!std::isfinite(geoid_undulation) || std::abs(geoid_undulation) > 150) {
    throw ConfigError(fmt::format("geoid_undulation {} m is not a plausible undulation (|N| <= 150 m)",
                                  geoid_undulation));
  }
  if (kind == "ellipsoidal") {
    if (geoid_undulation != 0) {
      throw ConfigError("geoid_undulation is only meaningful with vertical_datum = \"orthometric\"");
    }
    return {VerticalDatum::Kind::ellipsoidal, 0.0};
  }
  if (kind == "orthometric") return {VerticalDatum::Kind::orthometric, geoid_undulation};
  throw ConfigError(fmt::format("vertical_datum '{}': expected \"ellipsoidal\" or \"orthometric\"", kind));
}

}  // namespace citymesh
