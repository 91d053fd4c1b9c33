// Georeferencing against PROJ (cs2cs / cct from Debian's proj-bin) as an independent oracle,
// plus round trips, the local frame's exactness, and scanner poses.
//
// Each family projects a few thousand seeded points with our code and with cs2cs using the
// EPSG code (so PROJ takes its parameters from its own EPSG database, not from ours) and
// compares in metres. Tolerances: 1 mm for projections (measured agreement is printed as
// "[agreement]" lines); datum shifts as stated per test. Tests skip when cs2cs is missing.

#include <gtest/gtest.h>

#include <unistd.h>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <optional>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "csgtile/geo/crs.h"
#include "csgtile/geo/georeference.h"

namespace csgtile::geo {
namespace {

using kernel::Vec3;
using Triple = std::array<double, 3>;

constexpr double kPi = 3.14159265358979323846;
constexpr double kMetresPerDegree = 111320.0;  // for turning angle differences into metres

bool tool_available(const char* tool) {
  const std::string command = std::string("command -v ") + tool + " > /dev/null 2>&1";
  return std::system(command.c_str()) == 0;
}

// Runs `command` with one "a b c" line per input point on stdin; returns one triple per line
// (NaNs where the tool printed '*'), or nullopt when the tool failed.
std::optional<std::vector<Triple>> run_tool(const std::string& command,
                                            const std::vector<Triple>& input) {
  static int counter = 0;
  const std::string base =
      "/tmp/csgtile_geo_test_" + std::to_string(::getpid()) + "_" + std::to_string(counter++);
  {
    std::ofstream in(base + ".in");
    in.precision(17);
    for (const Triple& t : input) in << t[0] << ' ' << t[1] << ' ' << t[2] << '\n';
  }
  const std::string full = command + " < " + base + ".in > " + base + ".out 2> " + base + ".err";
  const int rc = std::system(full.c_str());
  std::vector<Triple> out;
  std::ifstream result(base + ".out");
  std::string line;
  while (std::getline(result, line)) {
    for (char& c : line) {
      if (c == '\t') c = ' ';
    }
    std::istringstream fields(line);
    std::string a, b, c;
    fields >> a >> b >> c;
    auto parse = [](const std::string& s) {
      char* end = nullptr;
      const double v = std::strtod(s.c_str(), &end);
      return (s.empty() || *end != '\0') ? std::nan("") : v;
    };
    out.push_back({parse(a), parse(b), parse(c)});
  }
  std::remove((base + ".in").c_str());
  std::remove((base + ".out").c_str());
  std::remove((base + ".err").c_str());
  if (rc != 0 || out.size() != input.size()) return std::nullopt;
  return out;
}

std::optional<std::vector<Triple>> cs2cs(const std::string& from, const std::string& to,
                                         const std::vector<Triple>& in) {
  return run_tool("cs2cs -f %.10f " + from + " " + to, in);
}

#define REQUIRE_PROJ()                                                                        \
  if (!tool_available("cs2cs") || !tool_available("cct")) {                                   \
    GTEST_SKIP()                                                                              \
        << "PROJ's cs2cs/cct not installed (apt-get install proj-bin): oracle tests skipped"; \
  }

Crs epsg(int code) {
  auto crs = crs_from_epsg(code);
  EXPECT_TRUE(crs.ok()) << code;
  return crs.value();
}

// Horizontal distance in metres between two geodetic positions (small differences).
double geodetic_gap_m(double lat1, double lon1, double lat2, double lon2) {
  const double dlon = std::remainder(lon1 - lon2, 360.0);
  return kMetresPerDegree * std::hypot(lat1 - lat2, dlon * std::cos(lat1 * kPi / 180.0));
}

struct Family {
  const char* name;
  int projected;
  int geographic;       // the projected CRS's own base (no datum shift in cs2cs)
  bool northing_first;  // authority axis order of the projected CRS
  double lat_min, lat_max, lon_min, lon_max;
};

struct Agreement {
  double forward_m = 0, inverse_m = 0, round_trip_m = 0;
};

std::vector<Triple> random_geodetic(const Family& f, int n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> lat(f.lat_min, f.lat_max), lon(f.lon_min, f.lon_max);
  std::vector<Triple> points;
  for (int i = 0; i < n; ++i) points.push_back({lat(rng), lon(rng), 0.0});
  return points;
}

// Forward (ours vs cs2cs), inverse (ours on cs2cs's projected vs the input), round trip.
std::optional<Agreement> compare_family(const Family& f, int n = 2500) {
  const Crs crs = epsg(f.projected);
  const auto points = random_geodetic(f, n, 0x5eed0000u + static_cast<std::uint64_t>(f.projected));
  auto oracle =
      cs2cs("EPSG:" + std::to_string(f.geographic), "EPSG:" + std::to_string(f.projected), points);
  if (!oracle) return std::nullopt;
  const double unit = crs.linear_unit.metres;
  Agreement a;
  for (int i = 0; i < n; ++i) {
    const Triple& g = points[i];
    Triple o = (*oracle)[i];
    if (f.northing_first) std::swap(o[0], o[1]);
    EXPECT_TRUE(std::isfinite(o[0]) && std::isfinite(o[1]))
        << f.name << " cs2cs refused point " << i;
    auto mine = geodetic_to_projected(crs, GeodeticPoint{g[0], g[1], 0.0});
    EXPECT_TRUE(mine.ok()) << f.name << ": " << (mine.ok() ? "" : mine.error().message);
    if (!mine.ok()) continue;
    a.forward_m =
        std::max(a.forward_m, unit * std::hypot(mine.value().x() - o[0], mine.value().y() - o[1]));
    auto back = projected_to_geodetic(crs, Vec3(o[0], o[1], 0.0));
    EXPECT_TRUE(back.ok()) << f.name;
    if (back.ok()) {
      a.inverse_m = std::max(a.inverse_m, geodetic_gap_m(back.value().latitude_deg,
                                                         back.value().longitude_deg, g[0], g[1]));
    }
    auto round = projected_to_geodetic(crs, mine.value());
    if (round.ok()) {
      a.round_trip_m = std::max(
          a.round_trip_m,
          geodetic_gap_m(round.value().latitude_deg, round.value().longitude_deg, g[0], g[1]));
    }
  }
  std::cout << "[agreement] " << f.name << " (EPSG:" << f.projected << ", " << n
            << " points): forward max " << a.forward_m * 1e3 << " mm, inverse max "
            << a.inverse_m * 1e3 << " mm, round trip max " << a.round_trip_m * 1e9 << " nm\n";
  return a;
}

void expect_family(const Family& f, double tolerance_m = 1e-3, double round_trip_m = 1e-6) {
  auto a = compare_family(f);
  ASSERT_TRUE(a.has_value()) << "cs2cs failed for " << f.name;
  EXPECT_LT(a->forward_m, tolerance_m) << f.name;
  EXPECT_LT(a->inverse_m, tolerance_m) << f.name;
  EXPECT_LT(a->round_trip_m, round_trip_m) << f.name;
}

// ---- projections against cs2cs -----------------------------------------------------------

TEST(GeoProjectionVsCs2cs, UtmNorthWgs84UsesUtmups) {
  REQUIRE_PROJ();
  // Within GeographicLib's legal UTM bounds (easting 0-1000 km), which UTMUPS enforces.
  expect_family({"UTM 31N WGS 84", 32631, 4326, false, 0.0, 84.0, -1.0, 7.0});
}

TEST(GeoProjectionVsCs2cs, UtmSouthWgs84) {
  REQUIRE_PROJ();
  expect_family({"UTM 33S WGS 84", 32733, 4326, false, -80.0, -0.01, 11.0, 19.0});
}

TEST(GeoProjectionVsCs2cs, UtmEtrs89AndNad83UseTransverseMercatorOnGrs80) {
  REQUIRE_PROJ();
  expect_family({"UTM 32N ETRS89", 25832, 4258, false, 35.0, 72.0, 5.0, 13.0});
  expect_family({"UTM 10N NAD83", 26910, 4269, false, 30.0, 60.0, -127.0, -119.0});
}

TEST(GeoProjectionVsCs2cs, UpsNorthAndSouth) {
  REQUIRE_PROJ();
  expect_family({"UPS North", 32661, 4326, true, 83.5, 89.999, -180.0, 180.0});
  expect_family({"UPS South", 32761, 4326, true, -89.999, -79.5, -180.0, 180.0});
}

TEST(GeoProjectionVsCs2cs, TransverseMercatorWithLatitudeOfOrigin) {
  REQUIRE_PROJ();
  expect_family({"NZTM2000", 2193, 4167, true, -47.5, -34.0, 166.0, 179.0});
  expect_family({"Irish TM", 2157, 4173, false, 51.0, 55.5, -11.0, -5.0});
  expect_family({"British National Grid (Airy)", 27700, 4277, false, 49.8, 60.0, -8.0, 2.0});
  expect_family({"Florida East ftUS", 2236, 4269, false, 24.0, 31.0, -82.5, -79.5});
  expect_family({"New Mexico Central ftUS", 2903, 4152, false, 31.0, 37.0, -107.8, -104.5});
}

TEST(GeoProjectionVsCs2cs, LambertConicInFeet) {
  REQUIRE_PROJ();
  expect_family({"NY Long Island ftUS", 2263, 4269, false, 40.3, 41.5, -74.5, -71.5});
  expect_family({"California 5 ftUS", 2229, 4269, false, 32.5, 35.8, -121.0, -114.0});
  expect_family({"Oregon GIC Lambert ft", 2992, 4269, false, 41.8, 46.3, -124.8, -116.4});
  expect_family({"Oregon GIC Lambert ft HARN", 2994, 4152, false, 41.8, 46.3, -124.8, -116.4});
  expect_family({"Lambert-93", 2154, 4171, false, 41.0, 51.5, -5.5, 10.0});
  expect_family({"Texas Centric LCC", 6580, 6318, false, 25.8, 36.5, -106.6, -93.5});
}

// National grids resolved through PROJ's database (issue #19), checked against cs2cs.
TEST(GeoProjectionVsCs2cs, NationalGridsFromProjsDatabase) {
  REQUIRE_PROJ();
  expect_family({"ETRS89 / TM35FIN", 3067, 4258, false, 60.0, 69.5, 20.0, 31.0});
  expect_family({"BD72 / Belgian Lambert 72", 31370, 4313, false, 49.6, 51.4, 2.6, 6.3});
  expect_family({"ETRS89 / Poland CS92", 2180, 4258, true, 49.1, 54.8, 14.2, 24.1});
  // UTM 33's parameters, so computed as UTM: within its legal eastings (Sweden's land is).
  expect_family({"SWEREF99 TM", 3006, 4619, true, 55.3, 69.0, 11.0, 20.5});
  expect_family({"GDA2020 / MGA zone 56", 7856, 7844, false, -37.5, -10.0, 150.0, 156.0});
}

// Methods our own engines do not compute are computed by PROJ from its own definition
// (issue #19): Krovak, Swiss and Hotine oblique Mercator,
// Mercator (spherical and ellipsoidal), Lambert azimuthal equal area, Albers.
TEST(GeoProjectionVsCs2cs, MethodsComputedByProj) {
  REQUIRE_PROJ();
  expect_family({"S-JTSK / Krovak East North", 5514, 4156, false, 48.6, 51.0, 12.2, 18.8});
  expect_family({"CH1903+ / LV95", 2056, 4150, false, 45.9, 47.8, 6.0, 10.4});
  expect_family({"WGS 84 / Pseudo-Mercator", 3857, 4326, false, -80.0, 80.0, -179.0, 179.0});
  expect_family({"WGS 84 / World Mercator", 3395, 4326, false, -80.0, 80.0, -179.0, 179.0});
  // PROJ 9.1 inverts LAEA with a truncated authalic-latitude series: about 1 mm, for cs2cs too.
  expect_family({"ETRS89-extended / LAEA Europe", 3035, 4258, true, 35.0, 70.0, -10.0, 30.0}, 2e-3,
                2e-3);
  expect_family({"GDA94 / Australian Albers", 3577, 4283, false, -40.0, -12.0, 115.0, 150.0});
  expect_family({"GDM2000 / Peninsula RSO", 3375, 4742, false, 1.3, 6.7, 99.7, 104.5});
  const Crs krovak = epsg(5514);
  ASSERT_TRUE(krovak.projection.has_value());
  EXPECT_NE(krovak.projection->method_name.find("Krovak"), std::string::npos);
  EXPECT_NE(describe_crs(krovak).find("Krovak"), std::string::npos) << describe_crs(krovak);
}

// A tile in a CRS computed by PROJ georeferences like one in a table CRS: the same points
// given in Krovak and in UTM 33N land on the same local coordinates (to the datum shifts'
// difference, which the two CRSs share here: both on ETRS89-related S-JTSK Helmert / WGS 84).
TEST(GeoProjectionVsCs2cs, BulkTransformOfAProjCrsMatchesOnePointAtATime) {
  REQUIRE_PROJ();
  const Crs krovak = epsg(5514);
  auto geo = Georeferencer::create_at(krovak, Vec3(-743000.0, -1043000.0, 250.0));
  ASSERT_TRUE(geo.ok()) << geo.error().message;
  std::vector<Vec3> in;
  for (int i = 0; i < 3000; ++i) {
    in.emplace_back(-743000.0 + (i % 60) * 17.0, -1043000.0 + (i / 60) * 13.0, 250.0 + i % 7);
  }
  std::vector<Vec3> bulk(in.size());
  ASSERT_TRUE(geo.value().to_local(in, bulk).ok());
  double worst = 0.0;
  for (std::size_t i = 0; i < in.size(); ++i) {
    worst = std::max(worst, (bulk[i] - geo.value().to_local(in[i])).norm());
  }
  EXPECT_LT(worst, 1e-9);
  // The round trip through PROJ's inverse and forward.
  double trip = 0.0;
  for (std::size_t i = 0; i < in.size(); i += 37) {
    trip = std::max(trip, (geo.value().to_source(bulk[i]) - in[i]).norm());
  }
  EXPECT_LT(trip, 1e-6);
  // A point outside the projection's domain is named by its index.
  in[1234] = Vec3(std::nan(""), -1043000.0, 0.0);
  auto refused = geo.value().to_local(in, bulk);
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.error().message.find("point 1234"), std::string::npos)
      << refused.error().message;
}

// Geocentric coordinates (EPSG:4978, WGS 84 ECEF) are a CRS too: a point's ECEF gives the
// frame position of its geodetic coordinates.
TEST(GeoGeographic, GeocentricCrsPlacesEcefPoints) {
  const Crs ecef = epsg(4978);
  EXPECT_EQ(ecef.kind, CrsKind::Geocentric);
  const Crs wgs84 = epsg(4979);
  const GeodeticPoint origin{52.0, 4.36, 40.0};
  auto a = Georeferencer::create(ecef, origin);
  auto b = Georeferencer::create(wgs84, origin);
  ASSERT_TRUE(a.ok() && b.ok()) << (a.ok() ? "" : a.error().message);
  for (const GeodeticPoint& g :
       {GeodeticPoint{52.001, 4.361, 55.0}, GeodeticPoint{51.99, 4.35, -3.0}}) {
    const Vec3 via_geodetic = b.value().to_local(Vec3(g.longitude_deg, g.latitude_deg, g.height_m));
    const Vec3 e = geodetic_to_ecef(Ellipsoid{}, g);
    EXPECT_LT((a.value().to_local(e) - via_geodetic).norm(), 1e-6);
    EXPECT_LT((a.value().to_source(via_geodetic) - e).norm(), 1e-6);
  }
  EXPECT_NE(crs_to_wkt1(ecef).find("GEOCCS"), std::string::npos);
  auto again = crs_from_wkt(crs_to_wkt1(ecef));
  ASSERT_TRUE(again.ok()) << again.error().message;
  EXPECT_FALSE(crs_difference(ecef, again.value()).has_value());
}

// User-defined projections in GeoTIFF keys (3075) that PROJ computes for us: the keys become
// a PROJ string on the datum's ellipsoid; cs2cs with the equivalent PROJ string is the oracle.
TEST(GeoProjectionVsCs2cs, GeoTiffUserDefinedMethodsComputedByProj) {
  REQUIRE_PROJ();
  auto k = [](std::uint16_t id, double v) { return GeoKeyEntry{id, {v}, {}}; };
  struct Case {
    const char* name;
    std::vector<GeoKeyEntry> projection;  // 3075 and its parameters
    std::string oracle;                   // the same projection for cs2cs
    double lat, lon;
  };
  const std::vector<Case> cases = {
      {"Albers (CONUS)",
       {k(3075, 11), k(3078, 29.5), k(3079, 45.5), k(3081, 23), k(3080, -96), k(3082, 0),
        k(3083, 0)},
       "+proj=aea +lat_1=29.5 +lat_2=45.5 +lat_0=23 +lon_0=-96 +x_0=0 +y_0=0 +ellps=GRS80",
       38.0,
       -100.0},
      {"LAEA (Europe)",
       {k(3075, 10), k(3089, 52), k(3088, 10), k(3082, 4321000), k(3083, 3210000)},
       "+proj=laea +lat_0=52 +lon_0=10 +x_0=4321000 +y_0=3210000 +ellps=GRS80",
       48.0,
       2.0},
      {"Mercator 1SP",
       {k(3075, 7), k(3080, 110), k(3092, 0.997), k(3082, 3900000), k(3083, 900000)},
       "+proj=merc +lon_0=110 +k_0=0.997 +x_0=3900000 +y_0=900000 +ellps=GRS80",
       -5.0,
       112.0},
      {"Cassini-Soldner",
       {k(3075, 18), k(3081, 10.44), k(3080, -61.33), k(3082, 86501.46), k(3083, 65379.0)},
       "+proj=cass +lat_0=10.44 +lon_0=-61.33 +x_0=86501.46 +y_0=65379 +ellps=GRS80",
       10.6,
       -61.2},
      {"Equirectangular",
       {k(3075, 17), k(3078, 30), k(3080, 0)},
       "+proj=eqc +lat_ts=30 +lon_0=0 +x_0=0 +y_0=0 +ellps=GRS80",
       40.0,
       20.0},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    std::vector<GeoKeyEntry> keys = {k(1024, 1), k(2048, 4269), k(3072, 32767), k(3074, 32767),
                                     k(3076, 9001)};
    keys.insert(keys.end(), c.projection.begin(), c.projection.end());
    auto crs = crs_from_geokeys(keys);
    ASSERT_TRUE(crs.ok()) << crs.error().message;
    std::vector<Triple> points;
    for (int i = 0; i < 50; ++i) points.push_back({c.lat + 0.02 * i, c.lon - 0.03 * i, 0.0});
    auto oracle = cs2cs("+proj=longlat +ellps=GRS80", "+to " + c.oracle, [&] {
      std::vector<Triple> lonlat;
      for (const Triple& p : points) lonlat.push_back({p[1], p[0], 0.0});
      return lonlat;
    }());
    ASSERT_TRUE(oracle.has_value());
    double worst = 0;
    for (std::size_t i = 0; i < points.size(); ++i) {
      auto mine = geodetic_to_projected(crs.value(), GeodeticPoint{points[i][0], points[i][1], 0});
      ASSERT_TRUE(mine.ok()) << mine.error().message;
      worst = std::max(worst, std::hypot(mine.value().x() - (*oracle)[i][0],
                                         mine.value().y() - (*oracle)[i][1]));
    }
    EXPECT_LT(worst, 1e-6) << c.name;
    // Written as WKT 1 (by PROJ) and read back: the same CRS.
    auto again = crs_from_wkt(crs_to_wkt1(crs.value()));
    ASSERT_TRUE(again.ok()) << again.error().message << "\n" << crs_to_wkt1(crs.value());
    auto back = geodetic_to_projected(again.value(), GeodeticPoint{points[0][0], points[0][1], 0});
    ASSERT_TRUE(back.ok());
    EXPECT_LT(std::hypot(back.value().x() - (*oracle)[0][0], back.value().y() - (*oracle)[0][1]),
              1e-6);
  }
}

// The Japanese plane rectangular systems (northing-first axes), as in the pnext test files.
TEST(GeoProjectionVsCs2cs, JapanPlaneRectangular) {
  REQUIRE_PROJ();
  expect_family({"Japan PRCS I", 6669, 6668, true, 31.0, 34.5, 128.5, 130.5});
  expect_family({"Japan PRCS VIII", 6676, 6668, true, 35.0, 38.5, 137.5, 139.5});
  expect_family({"Japan PRCS XIII", 6681, 6668, true, 42.0, 45.5, 143.0, 145.5});
}

TEST(GeoProjectionVsCs2cs, PolarStereographicVariantB) {
  REQUIRE_PROJ();
  expect_family({"Antarctic PS", 3031, 4326, false, -89.999, -60.0, -180.0, 180.0});
  expect_family({"NSIDC PS North", 3413, 4326, false, 60.0, 89.999, -180.0, 180.0});
}

TEST(GeoProjectionVsCs2cs, LambertConic1SpFromWktAgrees) {
  REQUIRE_PROJ();
  // A user-defined LCC 1SP (no EPSG code for PROJ to look up): the same WKT goes to both.
  const std::string wkt =
      "PROJCS[\"test LCC 1SP\",GEOGCS[\"NAD83\",DATUM[\"North_American_Datum_1983\",SPHEROID[\"GRS "
      "1980\","
      "6378137,298.257222101]],PRIMEM[\"Greenwich\",0],UNIT[\"degree\",0.0174532925199433]],"
      "PROJECTION[\"Lambert_Conformal_Conic_1SP\"],PARAMETER[\"latitude_of_origin\",18],"
      "PARAMETER[\"central_meridian\",-77],PARAMETER[\"scale_factor\",0.99999],"
      "PARAMETER[\"false_easting\",250000],PARAMETER[\"false_northing\",150000],UNIT[\"metre\",1]]";
  auto crs = crs_from_wkt(wkt);
  ASSERT_TRUE(crs.ok()) << crs.error().message;
  ASSERT_EQ(crs.value().projection->method_name, "Lambert Conic Conformal (1SP)");
  const Family f{"LCC 1SP (WKT)", 0, 0, false, 14.0, 22.0, -82.0, -72.0};
  const auto points = random_geodetic(f, 2000, 77);
  auto oracle = cs2cs("EPSG:4269", "'" + wkt + "'", points);
  ASSERT_TRUE(oracle.has_value());
  double worst = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    auto mine = geodetic_to_projected(crs.value(), GeodeticPoint{points[i][0], points[i][1], 0});
    ASSERT_TRUE(mine.ok());
    worst = std::max(
        worst, std::hypot(mine.value().x() - (*oracle)[i][0], mine.value().y() - (*oracle)[i][1]));
  }
  std::cout << "[agreement] LCC 1SP (WKT, 2000 points): forward max " << worst * 1e3 << " mm\n";
  EXPECT_LT(worst, 1e-3);
}

TEST(GeoWktWriter, Cs2csReadsOurWktLikeTheEpsgCode) {
  REQUIRE_PROJ();
  struct Case {
    int code;
    int geographic;
    double lat, lon;
  };
  for (const Case& c :
       {Case{2263, 4269, 40.8, -73.2}, Case{3031, 4326, -75.0, 30.0}, Case{2157, 4173, 53.3, -6.3},
        Case{32631, 4326, 48.8, 2.3}, Case{2994, 4152, 44.05, -123.07}}) {
    const Crs crs = epsg(c.code);
    const std::string wkt = crs_to_wkt1(crs);
    const std::vector<Triple> in = {{c.lat, c.lon, 0.0}};
    const std::string from = "EPSG:" + std::to_string(c.geographic);
    auto via_code = cs2cs(from, "EPSG:" + std::to_string(c.code), in);
    auto via_wkt = cs2cs(from, "'" + wkt + "'", in);
    ASSERT_TRUE(via_code && via_wkt) << c.code;
    const double unit = crs.linear_unit.metres;
    // Our WKT is easting-first; so are the EPSG codes used here.
    EXPECT_NEAR((*via_code)[0][0], (*via_wkt)[0][0], 1e-3 / unit) << c.code << " " << wkt;
    EXPECT_NEAR((*via_code)[0][1], (*via_wkt)[0][1], 1e-3 / unit) << c.code;
  }
}

// ---- geographic and ECEF -----------------------------------------------------------------

TEST(GeoGeographic, EcefAgreesWithCs2csOnWgs84AndGrs80) {
  REQUIRE_PROJ();
  std::mt19937_64 rng(4979);
  std::uniform_real_distribution<double> lat(-89.9, 89.9), lon(-180, 180), h(-100, 9000);
  std::vector<Triple> points;
  for (int i = 0; i < 2000; ++i) points.push_back({lat(rng), lon(rng), h(rng)});
  for (auto [geographic, geocentric, ellipsoid_code] :
       {std::tuple{4979, 4978, 4326}, std::tuple{4937, 4936, 4258}}) {
    auto oracle =
        cs2cs("EPSG:" + std::to_string(geographic), "EPSG:" + std::to_string(geocentric), points);
    ASSERT_TRUE(oracle.has_value());
    const Ellipsoid e = epsg(ellipsoid_code).datum.ellipsoid;
    double worst = 0, worst_back = 0;
    for (std::size_t i = 0; i < points.size(); ++i) {
      const GeodeticPoint g{points[i][0], points[i][1], points[i][2]};
      const Vec3 x = geodetic_to_ecef(e, g);
      const Vec3 o((*oracle)[i][0], (*oracle)[i][1], (*oracle)[i][2]);
      worst = std::max(worst, (x - o).norm());
      const GeodeticPoint back = ecef_to_geodetic(e, o);
      worst_back = std::max(worst_back, geodetic_gap_m(back.latitude_deg, back.longitude_deg,
                                                       g.latitude_deg, g.longitude_deg) +
                                            std::fabs(back.height_m - g.height_m));
    }
    std::cout << "[agreement] geodetic->ECEF EPSG:" << geographic << " (2000 points): max "
              << worst * 1e3 << " mm; ECEF->geodetic max " << worst_back * 1e3 << " mm\n";
    EXPECT_LT(worst, 1e-3);
    EXPECT_LT(worst_back, 1e-3);
  }
}

TEST(GeoGeographic, GeographicCrsCoordinatesAreLongitudeLatitude) {
  const Crs wgs84 = epsg(4326);
  auto g = projected_to_geodetic(wgs84, Vec3(5.5, 52.25, 12.0));
  ASSERT_TRUE(g.ok());
  EXPECT_DOUBLE_EQ(g.value().longitude_deg, 5.5);
  EXPECT_DOUBLE_EQ(g.value().latitude_deg, 52.25);
  EXPECT_DOUBLE_EQ(g.value().height_m, 12.0);
  auto bad = projected_to_geodetic(wgs84, Vec3(5.5, 95.0, 0.0));
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.error().code, kernel::ErrorCode::InvalidArgument);
  EXPECT_NE(bad.error().message.find("latitude"), std::string::npos);
}

// ---- RD New ------------------------------------------------------------------------------

TEST(RdNewProjection, MatchesTheWorkedExampleOfGuidanceNote72) {
  // EPSG GN 7-2 §3.2.3 example: φ = 53°N, λ = 6°E on Amersfoort → E 196105.283, N 557057.739.
  const Crs rd = epsg(28992);
  auto p = geodetic_to_projected(rd, GeodeticPoint{53.0, 6.0, 0.0});
  ASSERT_TRUE(p.ok());
  EXPECT_NEAR(p.value().x(), 196105.283, 5e-4);
  EXPECT_NEAR(p.value().y(), 557057.739, 5e-4);
  auto g = projected_to_geodetic(rd, Vec3(196105.283, 557057.739, 0.0));
  ASSERT_TRUE(g.ok());
  EXPECT_LT(geodetic_gap_m(g.value().latitude_deg, g.value().longitude_deg, 53.0, 6.0), 1e-3);
  // The origin maps to the false origin (PROJ's sterea: within a few nanometres).
  auto origin = geodetic_to_projected(
      rd, GeodeticPoint{52.0 + 9.0 / 60 + 22.178 / 3600, 5.0 + 23.0 / 60 + 15.5 / 3600, 0});
  ASSERT_TRUE(origin.ok());
  EXPECT_NEAR(origin.value().x(), 155000.0, 1e-8);
  EXPECT_NEAR(origin.value().y(), 463000.0, 1e-8);
}

TEST(RdNewProjection, ObliqueStereographicAgreesWithCs2cs) {
  REQUIRE_PROJ();
  // Amersfoort geographic → RD New: projection only, no datum shift involved.
  expect_family({"RD New oblique stereographic (Bessel)", 28992, 4289, false, 50.6, 53.7, 3.2, 7.3},
                1e-4);
}

// RD → ETRS89 lat/lon with our EPSG:9281 Helmert against cs2cs EPSG:28992 → EPSG:4937, which
// uses the same transformation when the RDNAPTRANS grid is absent (projinfo lists it first).
// A datum whose best transformation PROJ finds is a grid shift whose grid is installed
// (DHDN → WGS 84 by BETA2007, Debian proj-data): PROJ's own pipeline is used, as cs2cs uses it,
// and its name and accuracy are recorded; the datum's Helmert would be metres off.
TEST(ProjDatumShift, GridShiftsPROJChoosesAreApplied) {
  REQUIRE_PROJ();
  const Crs gk3 = epsg(31467);  // DHDN / 3-degree Gauss-Kruger zone 3
  ASSERT_FALSE(gk3.datum.to_wgs84_pipeline.empty()) << gk3.datum.to_wgs84_source;
  EXPECT_NE(gk3.datum.to_wgs84_pipeline.find("hgridshift"), std::string::npos)
      << gk3.datum.to_wgs84_pipeline;
  EXPECT_NE(gk3.datum.to_wgs84_source.find("accuracy"), std::string::npos);
  std::mt19937_64 rng(31467);
  std::uniform_real_distribution<double> x(3400000, 3600000), y(5300000, 5900000);
  std::vector<Triple> points;
  for (int i = 0; i < 1500; ++i) points.push_back({x(rng), y(rng), 0.0});
  // EPSG:31467's authority axis order is northing first, as cs2cs reads it.
  std::vector<Triple> northing_first;
  for (const Triple& p : points) northing_first.push_back({p[1], p[0], p[2]});
  auto oracle = cs2cs("EPSG:31467", "EPSG:4326", northing_first);
  ASSERT_TRUE(oracle.has_value());
  double worst = 0;
  const Crs wgs84 = epsg(4326);
  for (std::size_t i = 0; i < points.size(); ++i) {
    auto w = transform_point(gk3, wgs84, Vec3(points[i][0], points[i][1], 0.0));
    ASSERT_TRUE(w.ok()) << w.error().message;
    worst = std::max(
        worst, geodetic_gap_m(w.value().y(), w.value().x(), (*oracle)[i][0], (*oracle)[i][1]));
  }
  std::cout << "[agreement] DHDN GK3 -> WGS 84 (" << gk3.datum.to_wgs84_source << ") vs cs2cs: max "
            << worst * 1e3 << " mm\n";
  EXPECT_LT(worst, 1e-3);
  // And back through the pipeline's inverse.
  auto back = transform_point(wgs84, gk3, Vec3(9.0, 49.0, 0.0));
  ASSERT_TRUE(back.ok());
  auto again = transform_point(gk3, wgs84, back.value());
  ASSERT_TRUE(again.ok());
  EXPECT_LT(geodetic_gap_m(again.value().y(), again.value().x(), 49.0, 9.0), 1e-6);
}

// RD New reaches WGS 84 by the Helmert PROJ ranks first (EPSG:4833 "Amersfoort to WGS 84 (4)",
// 1 m: the RDNAPTRANS grid is not installed), which is what cs2cs EPSG:28992 → EPSG:4326 runs.
TEST(RdNewDatumShift, HelmertPROJChoosesAgreesWithCs2cs) {
  REQUIRE_PROJ();
  const Crs rd = epsg(28992);
  std::mt19937_64 rng(28992);
  std::uniform_real_distribution<double> x(13000, 278000), y(306000, 619000);
  std::vector<Triple> points;
  for (int i = 0; i < 2500; ++i) points.push_back({x(rng), y(rng), 0.0});
  auto oracle = cs2cs("EPSG:28992", "EPSG:4326", points);
  ASSERT_TRUE(oracle.has_value());
  double worst = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    auto g = projected_to_geodetic(rd, Vec3(points[i][0], points[i][1], points[i][2]));
    ASSERT_TRUE(g.ok());
    auto w = datum_to_wgs84(rd.datum, g.value());
    ASSERT_TRUE(w.ok());
    worst = std::max(worst, geodetic_gap_m(w.value().latitude_deg, w.value().longitude_deg,
                                           (*oracle)[i][0], (*oracle)[i][1]));
  }
  EXPECT_NE(rd.datum.to_wgs84_source.find("Amersfoort to WGS 84"), std::string::npos)
      << rd.datum.to_wgs84_source;
  std::cout << "[agreement] RD New -> WGS 84 (" << rd.datum.to_wgs84_source
            << ") vs cs2cs EPSG:28992->4326 (2500 points): max " << worst * 1e3 << " mm\n";
  EXPECT_LT(worst, 1e-3);

  // And back: cs2cs inverts the small-angle Helmert by transposition, we invert it exactly;
  // the two differ by second-order terms (|Ω|²·|X| ≈ 0.5 mm), so 2 mm here.
  std::vector<Triple> etrs;
  for (const Triple& t : *oracle) etrs.push_back({t[0], t[1], 0.0});
  auto back_oracle = cs2cs("EPSG:4326", "EPSG:28992", etrs);
  ASSERT_TRUE(back_oracle.has_value());
  double worst_back = 0;
  for (std::size_t i = 0; i < etrs.size(); ++i) {
    auto a = wgs84_to_datum(rd.datum, GeodeticPoint{etrs[i][0], etrs[i][1], 0.0});
    ASSERT_TRUE(a.ok());
    auto p = geodetic_to_projected(rd, a.value());
    ASSERT_TRUE(p.ok());
    worst_back = std::max(worst_back, std::hypot(p.value().x() - (*back_oracle)[i][0],
                                                 p.value().y() - (*back_oracle)[i][1]));
  }
  std::cout << "[agreement] WGS 84 -> RD New vs cs2cs EPSG:4326->28992: max " << worst_back * 1e3
            << " mm\n";
  EXPECT_LT(worst_back, 2e-3);
}

// ---- geoid models ------------------------------------------------------------------------

// A vertical CRS's heights become ellipsoidal through the geoid model PROJ chooses where its
// grid is installed: EGM96 height (EPSG:5773) by Debian proj-data's egm96_15.gtx, checked
// against cs2cs EPSG:4326+5773 → EPSG:4979 (issue #19: grids where installed).
TEST(GeoGeoid, Egm96HeightsBecomeEllipsoidalAsCs2csSays) {
  REQUIRE_PROJ();
  auto crs = crs_from_config("EPSG:4326+5773");
  ASSERT_TRUE(crs.ok()) << crs.error().message;
  ASSERT_TRUE(crs.value().vertical.has_value());
  if (crs.value().vertical->to_ellipsoidal_pipeline.empty()) {
    GTEST_SKIP() << "no EGM96 grid installed for PROJ (proj-data): "
                 << crs.value().vertical->to_ellipsoidal_source;
  }
  EXPECT_NE(crs.value().vertical->to_ellipsoidal_source.find("EGM96"), std::string::npos)
      << crs.value().vertical->to_ellipsoidal_source;
  std::mt19937_64 rng(5773);
  std::uniform_real_distribution<double> lat(-70, 70), lon(-179, 179), h(-20, 300);
  std::vector<Triple> points;  // cs2cs takes EPSG:4326's latitude, longitude order
  for (int i = 0; i < 500; ++i) points.push_back({lat(rng), lon(rng), h(rng)});
  auto oracle = cs2cs("EPSG:4326+5773", "EPSG:4979", points);
  ASSERT_TRUE(oracle.has_value());
  double worst = 0, largest_n = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    auto g = projected_to_geodetic(crs.value(), Vec3(points[i][1], points[i][0], points[i][2]));
    ASSERT_TRUE(g.ok()) << g.error().message;
    worst = std::max(worst, std::fabs(g.value().height_m - (*oracle)[i][2]));
    largest_n = std::max(largest_n, std::fabs(g.value().height_m - points[i][2]));
    // And back: the geoid model's inverse.
    auto back = geodetic_to_projected(crs.value(), g.value());
    ASSERT_TRUE(back.ok());
    EXPECT_NEAR(back.value().z(), points[i][2], 1e-6);
  }
  std::cout << "[agreement] EGM96 heights -> ellipsoidal vs cs2cs (500 points): max " << worst * 1e3
            << " mm (undulations up to " << largest_n << " m)\n";
  EXPECT_LT(worst, 1e-3);
  EXPECT_GT(largest_n, 10.0);  // the model was applied, not skipped
  // The tile frame sees the same heights: a point at H = 0 lies N above the frame's origin.
  auto georef = Georeferencer::create_at(crs.value(), Vec3(4.36, 52.0, 0.0));
  ASSERT_TRUE(georef.ok()) << georef.error().message;
  EXPECT_NEAR(georef.value().frame().origin.height_m, 43.5, 1.0);  // N at Delft (cs2cs: 43.477)
}

// Where no grid for the vertical CRS is installed, heights stay as they are and the CRS says so.
TEST(GeoGeoid, WithoutAGridHeightsAreTakenAsEllipsoidalWithAWarning) {
  auto crs = crs_from_config("EPSG:28992+5709");
  ASSERT_TRUE(crs.ok()) << crs.error().message;
  ASSERT_TRUE(crs.value().vertical.has_value());
  if (!crs.value().vertical->to_ellipsoidal_pipeline.empty()) {
    GTEST_SKIP() << "a NAP geoid grid is installed here: "
                 << crs.value().vertical->to_ellipsoidal_source;
  }
  EXPECT_NE(crs.value().vertical->to_ellipsoidal_source.find("none installed"), std::string::npos);
  bool warned = false;
  for (const auto& w : crs.value().warnings) warned |= w.find("NAP height") != std::string::npos;
  EXPECT_TRUE(warned);
  auto g = projected_to_geodetic(crs.value(), Vec3(85000, 446000, 12.5));
  ASSERT_TRUE(g.ok());
  EXPECT_DOUBLE_EQ(g.value().height_m, 12.5);
}

// ---- the local frame ---------------------------------------------------------------------

// Our to_local against a PROJ pipeline doing the same steps (inverse projection, cart,
// Helmert, topocentric) with EPSG parameters.
void expect_local_matches_cct(const Crs& crs, const Vec3& origin_xyz,
                              const std::string& inverse_projection_steps, double half_width,
                              std::uint64_t seed, const char* name) {
  auto georef = Georeferencer::create_at(crs, origin_xyz);
  ASSERT_TRUE(georef.ok()) << georef.error().message;
  const GeodeticPoint& o = georef.value().frame().origin;
  char topocentric[256];
  std::snprintf(topocentric, sizeof topocentric,
                " +step +proj=topocentric +ellps=WGS84 +lat_0=%.15f +lon_0=%.15f +h_0=%.9f",
                o.latitude_deg, o.longitude_deg, o.height_m);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> d(-half_width, half_width), h(-50, 300);
  std::vector<Triple> points;
  for (int i = 0; i < 2000; ++i)
    points.push_back({origin_xyz.x() + d(rng), origin_xyz.y() + d(rng), h(rng)});
  auto oracle =
      run_tool("cct -d 10 +proj=pipeline " + inverse_projection_steps + topocentric, points);
  ASSERT_TRUE(oracle.has_value()) << name;
  double worst = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Vec3 local = georef.value().to_local(Vec3(points[i][0], points[i][1], points[i][2]));
    worst =
        std::max(worst, (local - Vec3((*oracle)[i][0], (*oracle)[i][1], (*oracle)[i][2])).norm());
  }
  std::cout << "[agreement] " << name << " to_local vs cct pipeline (2000 points, ±" << half_width
            << " units): max " << worst * 1e3 << " mm\n";
  EXPECT_LT(worst, 1e-3) << name;
}

TEST(GeoLocalFrame, UtmToLocalMatchesProjTopocentric) {
  REQUIRE_PROJ();
  expect_local_matches_cct(
      epsg(32631), Vec3(640000, 5700000, 40),
      "+step +inv +proj=utm +zone=31 +ellps=WGS84 +step +proj=cart +ellps=WGS84", 2000, 1,
      "UTM 31N");
}

TEST(RdNewLocalFrame, RdToLocalMatchesProjPipelineWithHelmert) {
  REQUIRE_PROJ();
  // EPSG:4833 "Amersfoort to WGS 84 (4)", as projinfo -s EPSG:4289 -t EPSG:4326 writes it.
  const char* helmert =
      "+step +proj=helmert +x=565.4171 +y=50.3319 +z=465.5524 +rx=0.398957388243134 "
      "+ry=-0.343987817378283 +rz=1.87740163998045 +s=4.0725 +convention=coordinate_frame";
  expect_local_matches_cct(
      epsg(28992), Vec3(85000, 446000, 0),
      "+step +inv +proj=sterea +lat_0=52.156160555555555 +lon_0=5.387638888888889 "
      "+k=0.9999079 +x_0=155000 +y_0=463000 +ellps=bessel +step +proj=cart +ellps=bessel " +
          std::string(helmert),
      1500, 2, "RD New (Delft)");
}

// NAD83 is identified with WGS 84 by carrying geodetic coordinates over (EPSG:1188, null),
// while this pipeline goes GRS 80 geodetic → ECEF directly: the two differ by the ellipsoids'
// flattening difference, about 0.1 mm, which is what this comparison measures.
TEST(GeoLocalFrame, LambertFeetToLocalMatchesProjTopocentric) {
  REQUIRE_PROJ();
  // z stays in metres in the pipeline: give the CRS a metre vertical unit.
  Crs crs = epsg(2263);
  crs.vertical = VerticalCrs{5703, "NAVD88 height", metre_unit()};
  expect_local_matches_cct(
      crs, Vec3(988000, 210000, 0),
      "+step +proj=unitconvert +xy_in=us-ft +xy_out=m +step +inv +proj=lcc "
      "+lat_0=40.166666666666667 "
      "+lon_0=-74 +lat_1=41.033333333333333 +lat_2=40.666666666666667 +x_0=300000 +y_0=0 "
      "+ellps=GRS80 +step +proj=cart +ellps=GRS80",
      6000, 3, "NY Long Island ftUS");
}

TEST(GeoLocalFrame, DistancesArePreservedNearTheOrigin) {
  // ENU is a rigid motion of ECEF: pairwise distances of local points equal those of the ECEF
  // points computed along an independent path (geodetic → ECEF), to 1e-9 relative.
  for (int code : {32631, 28992, 2992}) {
    const Crs crs = epsg(code);
    const Vec3 origin = code == 32631   ? Vec3(640000, 5700000, 0)
                        : code == 28992 ? Vec3(121000, 487000, 0)
                                        : Vec3(635000, 851000, 400);
    auto georef = Georeferencer::create_at(crs, origin);
    ASSERT_TRUE(georef.ok());
    std::mt19937_64 rng(code);
    std::uniform_real_distribution<double> d(-1000 / crs.linear_unit.metres,
                                             1000 / crs.linear_unit.metres);
    std::vector<Vec3> local, ecef;
    for (int i = 0; i < 200; ++i) {
      const Vec3 p = origin + Vec3(d(rng), d(rng), d(rng) * 0.05);
      local.push_back(georef.value().to_local(p));
      auto g = projected_to_geodetic(crs, p);
      auto w = datum_to_wgs84(crs.datum, g.value());
      ecef.push_back(geodetic_to_ecef(epsg(4326).datum.ellipsoid, w.value()));
    }
    double worst = 0;
    for (std::size_t i = 0; i < local.size(); ++i) {
      for (std::size_t j = i + 1; j < local.size(); ++j) {
        const double a = (local[i] - local[j]).norm();
        const double b = (ecef[i] - ecef[j]).norm();
        worst = std::max(worst, std::fabs(a - b) / b);
      }
    }
    EXPECT_LT(worst, 1e-9) << code;
  }
}

TEST(GeoLocalFrame, LocationPlacesTheFrameExactlyInEcef) {
  const Crs crs = epsg(28992);
  auto georef = Georeferencer::create_at(crs, Vec3(121000, 487000, 2));
  ASSERT_TRUE(georef.ok());
  const TileFrame& frame = georef.value().frame();
  EXPECT_EQ(frame.local_to_ecef.scale(), 1.0);
  EXPECT_NEAR((frame.local_to_ecef.rotation() * frame.local_to_ecef.rotation().transpose() -
               Eigen::Matrix3d::Identity())
                  .norm(),
              0.0, 1e-15);
  // The origin's up axis is the ellipsoid normal; the origin itself maps to local zero.
  const Vec3 p(121000, 487000, 2);
  EXPECT_LT(georef.value().to_local(p).norm(), 1e-6);
  for (const Vec3& q : {Vec3(121500, 487250, 10), Vec3(120200, 486100, -3)}) {
    const Vec3 local = georef.value().to_local(q);
    auto g = projected_to_geodetic(crs, q);
    auto w = datum_to_wgs84(crs.datum, g.value());
    const Vec3 ecef = geodetic_to_ecef(epsg(4326).datum.ellipsoid, w.value());
    EXPECT_LT((frame.local_to_ecef.apply_point(local) - ecef).norm(), 1e-8);
    EXPECT_LT((georef.value().ecef_to_local(ecef) - local).norm(), 1e-8);
  }
}

TEST(GeoLocalFrame, RoundTripsAcrossFamilies) {
  struct Case {
    int code;
    Vec3 origin;
  };
  for (const Case& c : {Case{32631, {640000, 5700000, 10}}, Case{32733, {500000, 6200000, 0}},
                        Case{32661, {2000000, 1500000, 0}}, Case{2263, {988000, 210000, 30}},
                        Case{2992, {635000, 851000, 400}}, Case{3031, {-1000000, 500000, 0}},
                        Case{28992, {85000, 446000, -4}}, Case{27700, {530000, 180000, 20}},
                        Case{4326, {4.36, 52.01, 0}}}) {
    const Crs crs = epsg(c.code);
    auto georef = Georeferencer::create_at(crs, c.origin);
    ASSERT_TRUE(georef.ok()) << c.code << ": " << georef.error().message;
    std::mt19937_64 rng(c.code);
    const double span = crs.is_projected() ? 3000 / crs.linear_unit.metres : 0.03;
    std::uniform_real_distribution<double> d(-span, span), h(-30, 300);
    double worst = 0;
    for (int i = 0; i < 1000; ++i) {
      const Vec3 p = c.origin + Vec3(d(rng), d(rng), h(rng));
      const Vec3 back = georef.value().to_source(georef.value().to_local(p));
      const Vec3 delta = back - p;
      const double horizontal = crs.is_projected()
                                    ? std::hypot(delta.x(), delta.y()) * crs.linear_unit.metres
                                    : std::hypot(delta.x(), delta.y()) * kMetresPerDegree;
      worst = std::max(worst, horizontal + std::fabs(delta.z()) * crs.z_unit_metres());
    }
    EXPECT_LT(worst, 1e-6) << c.code;
  }
}

TEST(GeoLocalFrame, FeetCoordinatesAndHeightsAreScaled) {
  const Crs crs = epsg(2263);  // US survey feet
  EXPECT_DOUBLE_EQ(crs.linear_unit.metres, 1200.0 / 3937.0);
  auto georef = Georeferencer::create_at(crs, Vec3(988000, 210000, 0));
  ASSERT_TRUE(georef.ok());
  const Vec3 up = georef.value().to_local(Vec3(988000, 210000, 100));
  EXPECT_NEAR(up.z(), 100 * 1200.0 / 3937.0, 1e-9);
  // 1000 ftUS east on the grid is 304.8006 m times the grid scale (LCC scale ~ 0.99997 here).
  const Vec3 east = georef.value().to_local(Vec3(989000, 210000, 0));
  EXPECT_NEAR(east.norm(), 304.8006096, 0.05);
}

TEST(GeoLocalFrame, SimilarityIsOnlyAnApproximation) {
  auto georef = Georeferencer::create_at(epsg(32631), Vec3(640000, 5700000, 0));
  ASSERT_TRUE(georef.ok());
  auto near = georef.value().fit_similarity(100);
  auto far = georef.value().fit_similarity(5000);
  ASSERT_TRUE(near.ok() && far.ok());
  EXPECT_LT(near.value().max_error_m, 2e-3);
  EXPECT_GT(far.value().max_error_m, 0.1);  // Earth curvature: ~2 m drop at 5 km
  EXPECT_GT(far.value().max_error_m, 100 * near.value().max_error_m);
  std::cout << "[info] UTM 31N similarity fit: max error " << near.value().max_error_m * 1e3
            << " mm at 100 m, " << far.value().max_error_m << " m at 5 km\n";
}

TEST(GeoLocalFrame, GeoidUndulationShiftsHeightsAndRoundTrips) {
  GeoreferenceOptions options;
  options.geoid_undulation_m = 43.0;
  auto with = Georeferencer::create(epsg(28992), GeodeticPoint{52.0, 4.36, 43.0}, options);
  auto without = Georeferencer::create(epsg(28992), GeodeticPoint{52.0, 4.36, 43.0});
  ASSERT_TRUE(with.ok() && without.ok());
  const Vec3 p(85000, 446000, 0);
  EXPECT_NEAR(with.value().to_local(p).z() - without.value().to_local(p).z(), 43.0, 1e-3);
  EXPECT_LT((with.value().to_source(with.value().to_local(p)) - p).norm(), 1e-6);
}

// ---- errors ------------------------------------------------------------------------------

TEST(GeoErrors, GeographicLibExceptionsBecomeTypedErrors) {
  // UTMUPS refuses a point far outside zone 31 (GeographicErr): NaN in bulk, a message when
  // checked.
  auto georef = Georeferencer::create_at(epsg(32631), Vec3(640000, 5700000, 0));
  ASSERT_TRUE(georef.ok());
  const Vec3 bad(640000, 95000000, 0);
  EXPECT_TRUE(georef.value().to_local(bad).hasNaN());
  auto checked = georef.value().to_local_checked(bad);
  ASSERT_FALSE(checked.ok());
  EXPECT_EQ(checked.error().code, kernel::ErrorCode::InvalidArgument);
  EXPECT_NE(checked.error().message.find("UTM zone 31N"), std::string::npos)
      << checked.error().message;

  std::vector<Vec3> in = {Vec3(640000, 5700000, 0), bad};
  std::vector<Vec3> out(2);
  auto status = georef.value().to_local(in, out);
  ASSERT_FALSE(status.ok());
  EXPECT_NE(status.error().message.find("point 1"), std::string::npos) << status.error().message;

  auto geo = geodetic_to_projected(epsg(32631), GeodeticPoint{91.0, 3.0, 0});
  ASSERT_FALSE(geo.ok());
  EXPECT_EQ(geo.error().code, kernel::ErrorCode::InvalidArgument);
}

TEST(GeoErrors, DatumWithoutWgs84RelationCannotBeGeoreferenced) {
  // A datum PROJ relates to nothing, on an ellipsoid other than WGS 84's.
  auto odd = crs_from_wkt(
      R"wkt(GEOGCS["odd",DATUM["D_Odd",SPHEROID["Clarke 1880",6378249.145,293.465]],PRIMEM["Greenwich",0],UNIT["Degree",0.0174532925199433]])wkt");
  ASSERT_TRUE(odd.ok()) << odd.error().message;
  auto georef = Georeferencer::create(odd.value(), GeodeticPoint{40, -100, 0});
  ASSERT_FALSE(georef.ok());
  EXPECT_EQ(georef.error().code, kernel::ErrorCode::Unsupported);
  EXPECT_NE(georef.error().message.find("Odd"), std::string::npos) << georef.error().message;
  // ... but it still converts within its own datum.
  auto p = projected_to_geodetic(odd.value(), Vec3(-100, 40, 0));
  EXPECT_TRUE(p.ok());
}

TEST(GeoErrors, BadFrameOriginAndBadCrs) {
  auto georef = Georeferencer::create(epsg(4326), GeodeticPoint{95, 0, 0});
  ASSERT_FALSE(georef.ok());
  EXPECT_EQ(georef.error().code, kernel::ErrorCode::InvalidArgument);
  Crs broken = epsg(32631);
  broken.projection->proj_string = "+proj=utm +zone=99";
  auto bad = Georeferencer::create(broken, GeodeticPoint{50, 3, 0});
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.error().message.find("+proj=utm +zone=99"), std::string::npos)
      << bad.error().message;
}

TEST(GeoTransform, TransformPointThroughTheHub) {
  // RD → UTM 31N (ETRS89 ≈ WGS 84) and back.
  const Crs rd = epsg(28992);
  const Crs utm = epsg(25831);
  auto there = transform_point(rd, utm, Vec3(121000, 487000, 0));
  ASSERT_TRUE(there.ok());
  auto back = transform_point(utm, rd, there.value());
  ASSERT_TRUE(back.ok());
  EXPECT_LT((back.value() - Vec3(121000, 487000, 0)).norm(), 1e-6);
}

// ---- scanner poses -----------------------------------------------------------------------

TEST(ScannerPose, AxesFollowTheDocumentedConvention) {
  const GeodeticPoint at{52.0, 4.36, 10.0};
  auto tile = Georeferencer::create(epsg(4326), at);
  ASSERT_TRUE(tile.ok());
  auto place = [&](double heading, double pitch, double roll) {
    auto s = ScannerPlacement::from_pose(tile.value(), ScannerPose{at, heading, pitch, roll});
    EXPECT_TRUE(s.ok());
    return s.value();
  };
  const double tol = 1e-9;
  EXPECT_LT((place(0, 0, 0).to_local(Vec3(10, 0, 0)) - Vec3(0, 10, 0)).norm(),
            tol);  // forward = north
  EXPECT_LT((place(90, 0, 0).to_local(Vec3(10, 0, 0)) - Vec3(10, 0, 0)).norm(),
            tol);  // heading 90 = east
  EXPECT_LT((place(90, 0, 0).to_local(Vec3(0, 1, 0)) - Vec3(0, 1, 0)).norm(),
            tol);  // left of east = north
  const double c = std::cos(30 * kPi / 180), s = std::sin(30 * kPi / 180);
  EXPECT_LT((place(0, 30, 0).to_local(Vec3(10, 0, 0)) - Vec3(0, 10 * c, 10 * s)).norm(),
            tol);  // nose up
  EXPECT_LT((place(0, 0, 90).to_local(Vec3(0, 1, 0)) - Vec3(0, 0, 1)).norm(),
            tol);  // right side down: left goes up
  EXPECT_LT((place(0, 0, 0).to_local(Vec3(0, 0, 2)) - Vec3(0, 0, 2)).norm(), tol);
}

TEST(ScannerPose, PoseAwayFromTheOriginIsRigidAndRoundTrips) {
  auto tile = Georeferencer::create_at(epsg(28992), Vec3(85000, 446000, 0));
  ASSERT_TRUE(tile.ok());
  // A scanner 400 m north-east of the tile origin.
  const GeodeticPoint scanner = tile.value().local_to_geodetic(Vec3(300, 260, 1.8));
  auto placement =
      ScannerPlacement::from_pose(tile.value(), ScannerPose{scanner, 37.5, -2.0, 1.25});
  ASSERT_TRUE(placement.ok());
  ASSERT_TRUE(placement.value().location().has_value());
  EXPECT_LT((placement.value().to_local(Vec3::Zero()) - Vec3(300, 260, 1.8)).norm(), 1e-6);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> d(-80, 80);
  Vec3 previous = Vec3::Zero(), previous_local = placement.value().to_local(previous);
  for (int i = 0; i < 500; ++i) {
    const Vec3 p(d(rng), d(rng), d(rng) * 0.2);
    const Vec3 l = placement.value().to_local(p);
    EXPECT_LT((placement.value().to_scanner(l) - p).norm(), 1e-9);
    EXPECT_NEAR((l - previous_local).norm(), (p - previous).norm(), 1e-9);
    previous = p;
    previous_local = l;
  }
  // Its up axis is the scanner's own ellipsoid normal, tilted against the tile's by the
  // angle between the normals (~400 m / 6371 km ≈ 6.3e-5 rad) — not the tile's up.
  auto level = ScannerPlacement::from_pose(tile.value(), ScannerPose{scanner, 0, 0, 0});
  const Vec3 up = level.value().location()->apply_direction(Vec3::UnitZ());
  EXPECT_NEAR(std::acos(up.z()), 396.0 / 6.371e6, 1e-5);
}

TEST(ScannerPose, ProjectedMatrixTakesTheExactPathAndRoundTrips) {
  const Crs crs = epsg(2263);
  auto tile = Georeferencer::create_at(crs, Vec3(988000, 210000, 0));
  ASSERT_TRUE(tile.ok());
  // Scanner axes rotated 30° about z, metres → US feet, placed at a projected point.
  const double f = 1.0 / crs.linear_unit.metres;
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.topLeftCorner<3, 3>() = f * Eigen::AngleAxisd(30 * kPi / 180, Vec3::UnitZ()).toRotationMatrix();
  m.topRightCorner<3, 1>() = Vec3(988500, 210400, 12);
  auto placement = ScannerPlacement::from_projected_matrix(tile.value(), m);
  ASSERT_TRUE(placement.ok());
  EXPECT_FALSE(placement.value().location().has_value());
  EXPECT_LT(
      (placement.value().to_local(Vec3::Zero()) - tile.value().to_local(Vec3(988500, 210400, 12)))
          .norm(),
      1e-9);
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> d(-50, 50);
  for (int i = 0; i < 300; ++i) {
    const Vec3 p(d(rng), d(rng), d(rng));
    EXPECT_LT((placement.value().to_scanner(placement.value().to_local(p)) - p).norm(), 1e-6);
  }
  Eigen::Matrix4d bad = m;
  bad(3, 0) = 0.5;
  EXPECT_FALSE(ScannerPlacement::from_projected_matrix(tile.value(), bad).ok());
  EXPECT_FALSE(ScannerPlacement::from_projected_matrix(tile.value(), Eigen::Matrix4d::Zero()).ok());
}

}  // namespace
}  // namespace csgtile::geo
