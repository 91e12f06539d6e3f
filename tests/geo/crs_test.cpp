// SPDX-License-Identifier: MIT
// Reference values computed independently with PROJ 9.1.1 (Debian proj-bin), e.g.
//   echo "651070 6860700 50" | cs2cs -f %.10f +proj=lcc +lat_0=46.5 +lon_0=3 +lat_1=49 +lat_2=44
//     +x_0=700000 +y_0=6600000 +ellps=GRS80 +to +proj=longlat +ellps=GRS80      (and +proj=geocent)
//   echo "100 200 10" | cct -d 10 +proj=pipeline +step +inv +proj=topocentric +ellps=WGS84
//     +lat_0=48.85 +lon_0=2.35 +h_0=40 +step +inv +proj=cart +ellps=WGS84
#include <gtest/gtest.h>

#include <cmath>

#include "citymesh/core/error.h"
#include "citymesh/geo/crs.h"

namespace citymesh {
namespace {

constexpr VerticalDatum kEllipsoidal{VerticalDatum::Kind::ellipsoidal, 0.0};
constexpr double kMetresPerDegree = 111'320.0;

struct Reference {
  const char* crs;
  Vec3d projected;
  double lat, lon;
};

/// Horizontal distance in metres between two geodetic positions a few millimetres apart.
double horizontal_error(double lat_a, double lon_a, double lat_b, double lon_b) {
  const double dy = (lat_a - lat_b) * kMetresPerDegree;
  const double dx = (lon_a - lon_b) * kMetresPerDegree * std::cos(lat_a * M_PI / 180.0);
  return std::hypot(dx, dy);
}

class CrsReference : public ::testing::TestWithParam<Reference> {};

TEST_P(CrsReference, ProjectedToGeodeticAndBackWithinOneMillimetre) {
  const Reference& r = GetParam();
  const Crs crs = Crs::parse(r.crs, kEllipsoidal);
  const Geodetic g = crs.to_geodetic(r.projected);
  EXPECT_LE(horizontal_error(g.lat, g.lon, r.lat, r.lon), 0.001) << r.crs;
  const Vec3d back = crs.from_geodetic({r.lat, r.lon, r.projected.z});
  EXPECT_LE(std::hypot(back.x - r.projected.x, back.y - r.projected.y), 0.001) << r.crs;
}

INSTANTIATE_TEST_SUITE_P(
    Proj, CrsReference,
    ::testing::Values(Reference{"EPSG:2154", {651070, 6860700, 50}, 48.8444873583, 2.3332872556},
                      Reference{"EPSG:2154", {700000, 6600000, 0}, 46.5, 3.0},
                      Reference{"EPSG:2154", {1000000, 7000000, 300}, 50.0268908195, 7.1846151226},
                      Reference{"EPSG:2154", {200000, 6200000, -10}, 42.7255734383, -3.1036148909},
                      Reference{"EPSG:32631", {448251.898, 5411943.794, 0}, 48.8583000017, 2.2944999960},
                      Reference{"EPSG:32631", {500000, 0, 0}, 0.0, 3.0},
                      Reference{"EPSG:32733", {300000, 6000000, 120}, -36.1240958321, 12.7776086146},
                      Reference{"EPSG:32660", {700000, 7000000, 0}, 63.0739966029, -179.0396479968},
                      Reference{"EPSG:32601", {250000, 4000000, 0}, 36.1125055601, -179.7774602861}));

TEST(Crs, EcefMatchesProjWithinOneMillimetre) {
  struct Case {
    const char* crs;
    Vec3d p, ecef;
  };
  const Case cases[] = {
      {"EPSG:2154", {651070, 6860700, 50}, {4202017.85573, 171215.72218, 4779232.62219}},
      {"EPSG:2154", {1000000, 7000000, 300}, {4073527.93792, 513495.02336, 4864941.01201}},
      {"EPSG:32733", {300000, 6000000, 120}, {5030256.84875, 1140779.18688, -3739393.56162}},
      {"ENU:48.85,2.35,40", {100, 200, 10}, {4201351.95199, 172516.22515, 4779767.65656}},
  };
  for (const Case& c : cases) {
    const Crs crs = Crs::parse(c.crs, kEllipsoidal);
    const Vec3d e = crs.to_ecef(c.p);
    EXPECT_LE(norm(e - c.ecef), 0.001) << c.crs;
    const Vec3d back = crs.from_ecef(c.ecef);
    EXPECT_LE(norm(back - c.p), 0.001) << c.crs;
  }
}

TEST(Crs, LocalEnuFrameMatchesProjTopocentric) {
  const Crs crs = Crs::parse("ENU:48.85,2.35,40", kEllipsoidal);
  const Geodetic g = crs.to_geodetic({100, 200, 10});
  EXPECT_LE(horizontal_error(g.lat, g.lon, 48.8517984282, 2.3513625980), 0.001);
  EXPECT_NEAR(g.height, 50.0039212964, 0.001);
  EXPECT_TRUE(crs.is_local_frame());
}

TEST(Crs, OrthometricHeightsAddTheGeoidUndulation) {
  const Crs ortho = Crs::parse("EPSG:2154", {VerticalDatum::Kind::orthometric, 44.6});
  const Crs ellip = Crs::parse("EPSG:2154", kEllipsoidal);
  const Vec3d p{651070, 6860700, 5.4};
  EXPECT_NEAR(ortho.to_geodetic(p).height, 50.0, 1e-9);
  EXPECT_LE(norm(ortho.to_ecef(p) - ellip.to_ecef({651070, 6860700, 50})), 1e-6);
  EXPECT_NEAR(ortho.from_geodetic({48.84, 2.33, 50.0}).z, 5.4, 1e-9);
}

TEST(Crs, HeightsWithoutAVerticalDatumAreRefused) {
  const Crs crs = Crs::parse("EPSG:2154");
  EXPECT_NO_THROW((void)crs.to_lat_lon({651070, 6860700, 50}));  // lat/lon need no datum
  EXPECT_THROW((void)crs.to_ecef({651070, 6860700, 50}), ConfigError);
  EXPECT_THROW((void)crs.to_geodetic({651070, 6860700, 50}), ConfigError);
}

TEST(Crs, ProjectedMetresAreNotALocalFrame) {
  // A point 100 m east in Lambert-93 is not 100 m east of the origin in ECEF-tangent terms
  // only by accident: the projection's scale factor differs from 1.
  const Crs crs = Crs::parse("EPSG:2154", kEllipsoidal);
  EXPECT_FALSE(crs.is_local_frame());
  const double d = norm(crs.to_ecef({651170, 6860700, 50}) - crs.to_ecef({651070, 6860700, 50}));
  EXPECT_GT(std::abs(d - 100.0), 0.001);  // Lambert-93 scale near Paris is about 0.99993
}

TEST(Crs, RefusesUnsupportedSpecs) {
  for (const char* s : {"EPSG:4326", "EPSG:32600", "EPSG:32661", "EPSG:2154x", "ENU:48.8,2.3", "ENU:91,0,0",
                        "lambert", ""}) {
    EXPECT_THROW(Crs::parse(s), ConfigError) << s;
  }
  EXPECT_EQ(Crs::parse("EPSG:32733").name(), "WGS 84 / UTM zone 33S");
}

TEST(Crs, AreaOfUseHoldsItsRegionAndNotAnotherCrssCoordinates) {
  const Crs lambert = Crs::parse("EPSG:2154");
  const AreaOfUse france = lambert.area_of_use();
  EXPECT_TRUE(france.holds(lambert.to_lat_lon({651000, 6860700, 40})));   // Paris
  EXPECT_TRUE(france.holds(lambert.to_lat_lon({1230000, 6100000, 0})));   // Corsica
  EXPECT_FALSE(france.holds(lambert.to_lat_lon({2.3522, 48.8566, 35})));  // lon/lat as metres
  EXPECT_FALSE(france.holds(lambert.to_lat_lon({500000, 4000000, 0})));   // Lambert's north-south reach
  EXPECT_FALSE(france.holds({.lat = std::nan(""), .lon = 2.35, .height = 0}));

  const Crs utm31n = Crs::parse("EPSG:32631");
  const AreaOfUse zone31 = utm31n.area_of_use();
  EXPECT_TRUE(zone31.holds({.lat = 48.85, .lon = 2.35, .height = 0}));
  EXPECT_TRUE(zone31.holds({.lat = 48.85, .lon = 7.0, .height = 0}));  // a little past the band's edge
  EXPECT_FALSE(zone31.holds({.lat = 48.85, .lon = 12.0, .height = 0}));
  EXPECT_FALSE(zone31.holds({.lat = -20, .lon = 3.0, .height = 0}));  // the southern hemisphere
  EXPECT_TRUE(Crs::parse("EPSG:32731").area_of_use().holds({.lat = -20, .lon = 3.0, .height = 0}));
  // Zone 60's band reaches 180 degrees: data just across it (-179.5) is no mistake.
  EXPECT_TRUE(Crs::parse("EPSG:32760").area_of_use().holds({.lat = -40, .lon = -179.5, .height = 0}));

  const Crs enu = Crs::parse("ENU:48.8566,2.3522,35");
  EXPECT_TRUE(enu.area_of_use().holds(enu.to_lat_lon({20000, -30000, 0})));
  EXPECT_FALSE(enu.area_of_use().holds(enu.to_lat_lon({651000, 6860700, 40})));  // Lambert-93 metres
  // Near a pole a box of degrees would not hold the frame's surroundings: anywhere goes.
  EXPECT_TRUE(Crs::parse("ENU:89.5,0,0").area_of_use().holds({.lat = 89.9, .lon = 170, .height = 0}));
}

TEST(VerticalDatum, ParsesKindsAndChecksTheUndulation) {
  EXPECT_EQ(parse_vertical_datum("ellipsoidal", 0).kind, VerticalDatum::Kind::ellipsoidal);
  EXPECT_EQ(parse_vertical_datum("orthometric", 44.6).geoid_undulation, 44.6);
  EXPECT_THROW(parse_vertical_datum("geoid", 0), ConfigError);
  EXPECT_THROW(parse_vertical_datum("ellipsoidal", 3), ConfigError);
  EXPECT_THROW(parse_vertical_datum("orthometric", 500), ConfigError);
}

}  // namespace
}  // namespace citymesh
