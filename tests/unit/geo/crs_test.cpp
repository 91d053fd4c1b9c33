// CRS model as PROJ reads it: EPSG codes, GeoTIFF keys (inline and from the real LAS files in
// ../shared/data through a tiny raw-bytes VLR reader), WKT 1 / WKT 2, reconciliation, WKT 1
// as PROJ writes it, config text and validation.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <optional>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "csgtile/geo/crs.h"
#include "test_support.h"

namespace csgtile::geo {
namespace {

using kernel::ErrorCode;

GeoKeyEntry key(std::uint16_t id, double value) { return GeoKeyEntry{id, {value}, {}}; }
GeoKeyEntry text_key(std::uint16_t id, std::string text) {
  return GeoKeyEntry{id, {}, std::move(text)};
}

// A "+key=value" parameter of a projection's PROJ string (NaN when absent).
double param(const Crs& crs, const std::string& key) {
  const std::string& text = crs.projection->proj_string;
  const std::string needle = "+" + key + "=";
  for (std::size_t at = text.find(needle); at != std::string::npos;
       at = text.find(needle, at + 1)) {
    if (at == 0 || text[at - 1] == ' ') return std::stod(text.substr(at + needle.size()));
  }
  return std::nan("");
}

bool mentions(const std::vector<std::string>& warnings, const std::string& needle) {
  for (const auto& w : warnings) {
    if (w.find(needle) != std::string::npos) return true;
  }
  return false;
}

std::string all(const std::vector<std::string>& warnings) {
  std::string out;
  for (const auto& w : warnings) out += w + "\n";
  return out;
}

// ---- a tiny LAS VLR reader (test-only; the real reader belongs to the LAS module) -------

struct LasCrsRecords {
  std::optional<std::vector<GeoKeyEntry>> geokeys;
  std::optional<std::string> wkt;
};

template <class T>
bool read_at(const std::string& bytes, std::size_t offset, T& out) {
  if (offset + sizeof(T) > bytes.size()) return false;
  std::memcpy(&out, bytes.data() + offset, sizeof(T));
  return true;
}

std::optional<LasCrsRecords> read_las_crs(const std::filesystem::path& path) {
  const std::string bytes = test::read_file(path);
  if (bytes.size() < 227 || bytes.compare(0, 4, "LASF") != 0) return std::nullopt;
  std::uint16_t header_size = 0;
  std::uint32_t vlr_count = 0;
  read_at(bytes, 94, header_size);
  read_at(bytes, 100, vlr_count);
  struct Record {
    std::string user;
    std::uint16_t id;
    std::string body;
  };
  std::vector<Record> records;
  std::size_t p = header_size;
  for (std::uint32_t i = 0; i < vlr_count && p + 54 <= bytes.size(); ++i) {
    std::uint16_t id = 0, length = 0;
    read_at(bytes, p + 18, id);
    read_at(bytes, p + 20, length);
    const std::string user(bytes.c_str() + p + 2, strnlen(bytes.c_str() + p + 2, 16));
    if (p + 54 + length > bytes.size()) break;
    records.push_back({user, id, bytes.substr(p + 54, length)});
    p += 54 + length;
  }
  if (bytes[24] == 1 && bytes[25] >= 4) {  // LAS 1.4 EVLRs
    std::uint64_t start = 0;
    std::uint32_t count = 0;
    read_at(bytes, 235, start);
    read_at(bytes, 243, count);
    p = start;
    for (std::uint32_t i = 0; i < count && p + 60 <= bytes.size(); ++i) {
      std::uint16_t id = 0;
      std::uint64_t length = 0;
      read_at(bytes, p + 18, id);
      read_at(bytes, p + 20, length);
      const std::string user(bytes.c_str() + p + 2, strnlen(bytes.c_str() + p + 2, 16));
      if (length > bytes.size() || p + 60 + length > bytes.size()) break;
      records.push_back({user, id, bytes.substr(p + 60, length)});
      p += 60 + length;
    }
  }
  LasCrsRecords out;
  const std::string* doubles = nullptr;
  const std::string* ascii = nullptr;
  const std::string* directory = nullptr;
  for (const Record& r : records) {
    // liblas' copy of the WKT (user "liblas") stands in when the file has no LASF one.
    if (r.user == "liblas" && r.id == 2112 && !out.wkt) out.wkt = r.body;
    if (r.user != "LASF_Projection") continue;
    if (r.id == 34735) directory = &r.body;
    if (r.id == 34736) doubles = &r.body;
    if (r.id == 34737) ascii = &r.body;
    if (r.id == 2112) out.wkt = r.body;
  }
  if (directory) {
    std::vector<GeoKeyEntry> keys;
    std::uint16_t count = 0;
    read_at(*directory, 6, count);
    for (std::uint16_t i = 0; i < count; ++i) {
      std::uint16_t v[4];
      if (!read_at(*directory, 8 + 8u * i, v)) break;
      GeoKeyEntry e;
      e.id = v[0];
      if (v[1] == 0) {
        e.numbers.push_back(v[3]);
      } else if (v[1] == 34736 && doubles) {
        for (std::uint16_t k = 0; k < v[2]; ++k) {
          double d = 0;
          if (read_at(*doubles, 8u * (v[3] + k), d)) e.numbers.push_back(d);
        }
      } else if (v[1] == 34737 && ascii && v[3] < ascii->size()) {
        e.text = ascii->substr(v[3], v[2]);
      }
      keys.push_back(e);
    }
    out.geokeys = keys;
  }
  return out;
}

std::optional<LasCrsRecords> shared_file(const char* relative) {
  const auto path = test::shared_dir() / "data" / relative;
  if (!std::filesystem::exists(path)) return std::nullopt;
  return read_las_crs(path);
}

#define SHARED_FILE(var, relative)  \
  auto var = shared_file(relative); \
  if (!var) GTEST_SKIP() << "../shared/data/" << relative << " not present: skipped"

// ---- EPSG codes --------------------------------------------------------------------------

TEST(CrsEpsg, TheCityCodesResolve) {
  for (int code : {4326,  4979,  4258,  4937,  4269,  4152, 6318, 4289,  32601, 32660, 32701,
                   32760, 25828, 25838, 26901, 26923, 6330, 6348, 32661, 32761, 5041,  5042,
                   28992, 7415,  3031,  3413,  3976,  3995, 2193, 2157,  27700, 2154,  2991,
                   2992,  2994,  2269,  2270,  2913,  2227, 2229, 2263,  2236,  2903}) {
    auto crs = crs_from_epsg(code);
    ASSERT_TRUE(crs.ok()) << code << ": " << crs.error().message;
    EXPECT_TRUE(validate_crs(crs.value()).ok()) << code;
    EXPECT_EQ(crs.value().source, "EPSG:" + std::to_string(code));
  }
}

// Each job runs on a thread of its own; a thread's PROJ context is handed on to the threads
// after it. Threads one after another, and two at a time, read the same CRSs as this one.
TEST(CrsEpsg, ThreadsAfterThreadsReadTheSameCrs) {
  const auto read = [](int code) {
    auto crs = crs_from_epsg(code);
    return crs.ok() ? crs_to_wkt1(crs.value()) + "|" + crs.value().name : crs.error().message;
  };
  const std::string rd = read(28992), ny = read(2263);
  ASSERT_NE(rd.find("Amersfoort"), std::string::npos) << rd;
  for (int round = 0; round < 4; ++round) {
    std::string a, b;
    std::thread first([&] { a = read(28992); });
    std::thread second([&] { b = read(2263); });
    first.join();
    second.join();
    EXPECT_EQ(a, rd) << round;
    EXPECT_EQ(b, ny) << round;
  }
}

TEST(CrsEpsg, UnitsAndParameters) {
  const Crs ny = crs_from_epsg(2263).value();
  EXPECT_EQ(ny.linear_unit.epsg, 9003);
  EXPECT_DOUBLE_EQ(ny.linear_unit.metres, 1200.0 / 3937.0);
  EXPECT_DOUBLE_EQ(param(ny, "x_0"), 984250.0 * 1200.0 / 3937.0);
  EXPECT_NEAR(param(ny, "lat_0"), 40.0 + 10.0 / 60.0, 1e-12);
  const Crs oregon = crs_from_epsg(2992).value();
  EXPECT_DOUBLE_EQ(oregon.linear_unit.metres, 0.3048);
  EXPECT_EQ(oregon.projection->method_name, "Lambert Conic Conformal (2SP)");
  const Crs rd = crs_from_epsg(28992).value();
  EXPECT_EQ(rd.projection->method_name, "Oblique Stereographic");
  EXPECT_EQ(rd.datum.ellipsoid.epsg, 7004);
  ASSERT_TRUE(rd.datum.to_wgs84.has_value());
  // The Helmert PROJ ranks first for Amersfoort → WGS 84 (projinfo -s EPSG:4289 -t EPSG:4326).
  EXPECT_NE(rd.datum.to_wgs84_source.find("Amersfoort to WGS 84"), std::string::npos)
      << rd.datum.to_wgs84_source;
  EXPECT_NEAR(rd.datum.to_wgs84->tx_m, 565.4171, 1e-9);
  const Crs utm = crs_from_epsg(32733).value();
  EXPECT_DOUBLE_EQ(param(utm, "zone"), 33.0);
  EXPECT_NE(utm.projection->proj_string.find("+south"), std::string::npos);
  EXPECT_EQ(utm.name, "WGS 84 / UTM zone 33S");
  const Crs ups = crs_from_epsg(32761).value();
  EXPECT_EQ(ups.projection->method_name, "Polar Stereographic (variant A)");
  EXPECT_DOUBLE_EQ(param(ups, "lat_0"), -90.0);
  const Crs nap = crs_from_epsg(7415).value();
  ASSERT_TRUE(nap.vertical.has_value());
  EXPECT_EQ(nap.vertical->epsg, 5709);
  EXPECT_FALSE(crs_difference(nap, rd).has_value());
}

TEST(CrsEpsg, VerticalCodesAndUnknownCodes) {
  auto navd = crs_from_epsg(2263, 6360);
  ASSERT_TRUE(navd.ok());
  EXPECT_EQ(navd.value().vertical->name, "NAVD88 height (ftUS)");
  EXPECT_DOUBLE_EQ(navd.value().z_unit_metres(), 1200.0 / 3937.0);
  auto odd = crs_from_epsg(32631, 9999);  // no vertical CRS: an error naming the code
  ASSERT_FALSE(odd.ok());
  EXPECT_NE(odd.error().message.find("EPSG:9999"), std::string::npos);

  auto unknown = crs_from_epsg(99999);
  ASSERT_FALSE(unknown.ok());
  EXPECT_EQ(unknown.error().code, ErrorCode::Unsupported);
  EXPECT_NE(unknown.error().message.find("EPSG:99999"), std::string::npos);
  auto web = crs_from_epsg(3857);  // not in the table: PROJ's database
  ASSERT_TRUE(web.ok()) << web.error().message;
  EXPECT_NE(web.value().name.find("Pseudo-Mercator"), std::string::npos);
}

// Codes come from PROJ's database (issue #19): the national grids a city service meets, with
// the datum shift PROJ ranks first; every method PROJ computes, and geocentric CRSs.
TEST(CrsEpsg, NationalCodesFromProjsDatabase) {
  struct Case {
    int code;
    const char* name_part;
    const char* method;
  };
  for (const Case& c :
       {Case{3067, "TM35FIN", "Transverse Mercator"},
        Case{31370, "Belgian Lambert 72", "Lambert Conic Conformal (2SP)"},
        Case{2180, "CS92", "Transverse Mercator"}, Case{3006, "SWEREF99 TM", "Transverse Mercator"},
        Case{7856, "MGA zone 56", "Transverse Mercator"}}) {
    SCOPED_TRACE(c.code);
    auto crs = crs_from_epsg(c.code);
    ASSERT_TRUE(crs.ok()) << crs.error().message;
    EXPECT_EQ(crs.value().epsg, c.code);
    EXPECT_NE(crs.value().name.find(c.name_part), std::string::npos) << crs.value().name;
    ASSERT_TRUE(crs.value().projection.has_value());
    EXPECT_EQ(crs.value().projection->method_name, c.method);
    EXPECT_TRUE(crs.value().datum.to_wgs84.has_value()) << crs.value().datum.to_wgs84_source;
  }
  // BD72's shift is a real Helmert (metres of translation), named with its accuracy.
  const Crs lambert72 = crs_from_epsg(31370).value();
  EXPECT_GT(std::abs(lambert72.datum.to_wgs84->tx_m), 50.0);
  EXPECT_NE(lambert72.datum.to_wgs84_source.find("BD72 to WGS 84"), std::string::npos)
      << lambert72.datum.to_wgs84_source;
  EXPECT_NE(lambert72.datum.to_wgs84_source.find("accuracy"), std::string::npos);
  // A vertical CRS from the database: its name and unit, no warning.
  auto finland = crs_from_epsg(3067, 3900);
  ASSERT_TRUE(finland.ok()) << finland.error().message;
  ASSERT_TRUE(finland.value().vertical.has_value());
  EXPECT_NE(finland.value().vertical->name.find("N2000"), std::string::npos);
  EXPECT_FALSE(mentions(finland.value().warnings, "EPSG:3900"));
  // Methods our engines do not compute are PROJ's; geocentric CRSs are read too.
  for (const auto& [code, method] :
       std::vector<std::pair<int, std::string>>{{2056, "Oblique Mercator"},
                                                {5514, "Krovak"},
                                                {3857, "Pseudo Mercator"},
                                                {3035, "Lambert Azimuthal Equal Area"},
                                                {3577, "Albers"}}) {
    auto crs = crs_from_epsg(code);
    ASSERT_TRUE(crs.ok()) << code << ": " << crs.error().message;
    ASSERT_TRUE(crs.value().projection.has_value());
    EXPECT_NE(crs.value().projection->method_name.find(method), std::string::npos)
        << crs.value().projection->method_name;
    EXPECT_EQ(crs.value().epsg, code);
    EXPECT_TRUE(crs.value().datum.to_wgs84.has_value()) << crs.value().datum.to_wgs84_source;
  }
  auto ecef = crs_from_epsg(4978);
  ASSERT_TRUE(ecef.ok()) << ecef.error().message;
  EXPECT_EQ(ecef.value().kind, CrsKind::Geocentric);
  EXPECT_DOUBLE_EQ(ecef.value().z_unit_metres(), 1.0);
  EXPECT_FALSE(crs_from_epsg(4978, 5709).ok());  // no vertical CRS on geocentric coordinates
  auto none = crs_from_epsg(4099999);
  ASSERT_FALSE(none.ok());
  EXPECT_EQ(none.error().code, ErrorCode::Unsupported);
}

TEST(CrsEpsg, ZUnitFollowsVerticalThenHorizontal) {
  EXPECT_DOUBLE_EQ(crs_from_epsg(2992).value().z_unit_metres(), 0.3048);
  EXPECT_DOUBLE_EQ(crs_from_epsg(4326).value().z_unit_metres(), 1.0);
  EXPECT_DOUBLE_EQ(crs_from_epsg(2992, 5703).value().z_unit_metres(), 1.0);
}

// ---- GeoTIFF keys (values as the shared files carry them) --------------------------------

std::vector<GeoKeyEntry> autzen_trim_keys() {
  return {key(1024, 1),
          key(1025, 1),
          text_key(1026, "NAD_1983_HARN_Lambert_Conformal_Conic|"),
          key(2048, 32767),
          text_key(2049, "GCS Name = GCS_North_American_1983_HARN|Primem = Greenwich||"),
          key(2050, 6152),
          key(2054, 9102),
          key(2057, 6378137.0),
          key(2059, 298.257222101),
          key(2061, 0.0),
          key(3059, 1),
          key(3072, 32767),
          key(3074, 32767),
          key(3075, 8),
          key(3076, 9002),
          key(3078, 43.0),
          key(3079, 45.5),
          key(3084, -120.5),
          key(3085, 41.75),
          key(3086, 1312335.958005249),
          key(3087, 0.0)};
}

TEST(CrsGeoKeys, UserDefinedLambertInFeet) {
  auto crs = crs_from_geokeys(autzen_trim_keys());
  ASSERT_TRUE(crs.ok()) << crs.error().message;
  const Crs& c = crs.value();
  EXPECT_EQ(c.kind, CrsKind::Projected);
  EXPECT_EQ(c.projection->method_name, "Lambert Conic Conformal (2SP)");
  EXPECT_DOUBLE_EQ(c.linear_unit.metres, 0.3048);
  EXPECT_NEAR(param(c, "x_0"), 400000.0, 1e-6);
  EXPECT_EQ(c.datum.epsg, 6152);
  EXPECT_TRUE(mentions(c.warnings, "3059")) << all(c.warnings);  // an unknown key id
  // The same CRS as EPSG:2994 (NAD83(HARN) / Oregon GIC Lambert (ft)).
  EXPECT_EQ(crs_difference(c, crs_from_epsg(2994).value()), std::nullopt);
}

TEST(CrsGeoKeys, EpsgCodesWithVerticalCrs) {
  auto srs = crs_from_geokeys(
      {key(1024, 1), key(1025, 1), key(3072, 32617), key(3076, 9001), key(4096, 5703),
       text_key(4097, "North American Vertical Datum of 1988|"), key(4098, 5103), key(4099, 9001)});
  ASSERT_TRUE(srs.ok()) << srs.error().message;
  EXPECT_EQ(srs.value().epsg, 32617);
  ASSERT_TRUE(srs.value().vertical.has_value());
  EXPECT_EQ(srs.value().vertical->epsg, 5703);

  auto feet = crs_from_geokeys({key(1024, 1), key(1025, 2), key(3072, 2229),
                                text_key(4097, "NAVD88 via Geoid09|"), key(4099, 9003)});
  ASSERT_TRUE(feet.ok()) << feet.error().message;
  EXPECT_EQ(feet.value().epsg, 2229);
  EXPECT_DOUBLE_EQ(feet.value().z_unit_metres(), 1200.0 / 3937.0);
  EXPECT_EQ(feet.value().vertical->name, "NAVD88 via Geoid09");
}

TEST(CrsGeoKeys, UnknownEpsgCodeFallsBackToProjectionKeys) {
  // pdal/mvk-thin.las: EPSG:26995 (not in the table) with TM keys in US survey feet.
  auto crs =
      crs_from_geokeys({key(1024, 1),
                        key(2048, 4269),
                        key(2050, 6269),
                        key(2051, 8901),
                        key(2054, 9102),
                        key(2055, 0.017453292519943295),
                        key(2056, 7019),
                        key(2057, 6378137.0),
                        key(2059, 298.257222101),
                        key(2061, 0.0),
                        key(3072, 26995),
                        text_key(3073, "NAD_1983_StatePlane_Mississippi_West_FIPS_2302_Feet|"),
                        key(3075, 1),
                        key(3076, 9003),
                        key(3077, 0.30480060960121924),
                        key(3081, 29.5),
                        key(3082, 2296583.333333333),
                        key(3083, 0.0),
                        key(3088, -90.33333333333333),
                        key(3092, 0.99995),
                        text_key(4097, "NAVD88 - Geoid03 (Feet)|"),
                        key(4099, 9003)});
  ASSERT_TRUE(crs.ok()) << crs.error().message;
  const Crs& c = crs.value();
  EXPECT_TRUE(mentions(c.warnings, "EPSG:26995")) << all(c.warnings);
  EXPECT_EQ(c.projection->method_name, "Transverse Mercator");
  EXPECT_NEAR(param(c, "x_0"), 700000.0, 1e-6);
  EXPECT_DOUBLE_EQ(param(c, "lon_0"),
                   -90.33333333333333);  // from the "center" key
  EXPECT_DOUBLE_EQ(std::isnan(param(c, "k")) ? param(c, "k_0") : param(c, "k"), 0.99995);
  EXPECT_EQ(c.linear_unit.epsg, 9003);
  EXPECT_DOUBLE_EQ(c.z_unit_metres(), 1200.0 / 3937.0);
}

TEST(CrsGeoKeys, LinearUnitKeyOverridesTheEpsgUnitWithAWarning) {
  auto crs = crs_from_geokeys({key(1024, 1), key(3072, 26910), key(3076, 9002)});
  ASSERT_TRUE(crs.ok());
  EXPECT_DOUBLE_EQ(crs.value().linear_unit.metres, 0.3048);
  EXPECT_TRUE(mentions(crs.value().warnings, "overrides")) << all(crs.value().warnings);
}

TEST(CrsGeoKeys, ZeroAndUnknownKeysAreWarnings) {
  // pdal/bad-geotiff-keys.las: four zero entries after the real keys.
  auto crs = crs_from_geokeys({key(1024, 1), key(1025, 1), key(3072, 32617), key(3076, 9001),
                               GeoKeyEntry{0, {0}, {}}, GeoKeyEntry{0, {0}, {}},
                               GeoKeyEntry{0, {0}, {}}, GeoKeyEntry{0, {0}, {}}});
  ASSERT_TRUE(crs.ok());
  EXPECT_EQ(crs.value().epsg, 32617);
  EXPECT_TRUE(mentions(crs.value().warnings, "id 0")) << all(crs.value().warnings);
}

TEST(CrsGeoKeys, GeographicAndUserDefinedDatums) {
  auto wgs84 =
      crs_from_geokeys({key(1024, 2), key(1025, 1), key(2048, 4326), text_key(2049, "WGS 84|"),
                        key(2054, 9102), key(2057, 6378137.0), key(2059, 298.257223563)});
  ASSERT_TRUE(wgs84.ok());
  EXPECT_EQ(wgs84.value().kind, CrsKind::Geographic);
  EXPECT_TRUE(wgs84.value().warnings.empty()) << all(wgs84.value().warnings);

  // laspy/plane.las: user-defined everything on GRS 80 with a null TOWGS84.
  auto plane = crs_from_geokeys(
      {key(1024, 1),
       key(1025, 1),
       text_key(1026, "unnamed|"),
       key(2048, 32767),
       text_key(2049, "GCS Name = GRS 1980(IUGG, 1980)|Datum = unknown|Ellipsoid = GRS80|"),
       key(2050, 32767),
       key(2054, 9102),
       key(2056, 32767),
       key(2057, 6378137.0),
       key(2059, 298.257222101),
       key(2061, 0.0),
       GeoKeyEntry{2062, {0, 0, 0}, {}},
       key(3072, 32767),
       key(3074, 32767),
       key(3075, 8),
       key(3076, 9001),
       key(3078, 44.25),
       key(3079, 45.75),
       key(3084, 3.0),
       key(3085, 45.0),
       key(3086, 1700000.0),
       key(3087, 4200000.0)});
  ASSERT_TRUE(plane.ok()) << plane.error().message;
  ASSERT_TRUE(plane.value().datum.to_wgs84.has_value());
  EXPECT_TRUE(plane.value().datum.to_wgs84->is_null());
  EXPECT_EQ(plane.value().datum.ellipsoid.epsg, 7019);
  EXPECT_DOUBLE_EQ(param(plane.value(), "y_0"), 4200000.0);

  // A user-defined Bessel datum without TOWGS84 reads, but cannot be placed on the globe.
  auto bessel =
      crs_from_geokeys({key(1024, 2), key(2048, 32767), key(2050, 32767), key(2056, 7004)});
  ASSERT_TRUE(bessel.ok()) << bessel.error().message;
  EXPECT_FALSE(bessel.value().datum.to_wgs84.has_value());
  EXPECT_TRUE(mentions(bessel.value().warnings, "TOWGS84"));

  // TOWGS84 key in the position-vector convention becomes coordinate frame.
  auto shifted =
      crs_from_geokeys({key(1024, 2), key(2048, 32767), key(2050, 32767), key(2056, 7004),
                        GeoKeyEntry{2062, {565.2, 50.0, 465.6, -0.4, 0.35, -1.87, 4.08}, {}}});
  ASSERT_TRUE(shifted.ok());
  EXPECT_DOUBLE_EQ(shifted.value().datum.to_wgs84->rx_arcsec, 0.4);
  EXPECT_DOUBLE_EQ(shifted.value().datum.to_wgs84->rz_arcsec, 1.87);
}

TEST(CrsGeoKeys, PolarStereographicAndObliqueStereographicKeys) {
  auto ps = crs_from_geokeys({key(1024, 1), key(2048, 4326), key(3072, 32767), key(3075, 15),
                              key(3076, 9001), key(3081, -71.0), key(3095, 0.0), key(3092, 1.0),
                              key(3082, 0), key(3083, 0)});
  ASSERT_TRUE(ps.ok()) << ps.error().message;
  EXPECT_EQ(ps.value().projection->method_name, "Polar Stereographic (variant B)");
  EXPECT_EQ(crs_difference(ps.value(), crs_from_epsg(3031).value()), std::nullopt);

  auto rd =
      crs_from_geokeys({key(1024, 1), key(2048, 4289), key(3072, 32767), key(3075, 16),
                        key(3076, 9001), key(3081, 52.15616055555555), key(3080, 5.38763888888889),
                        key(3092, 0.9999079), key(3082, 155000), key(3083, 463000)});
  ASSERT_TRUE(rd.ok()) << rd.error().message;
  EXPECT_EQ(crs_difference(rd.value(), crs_from_epsg(28992).value()), std::nullopt);
}

TEST(CrsGeoKeys, ErrorsNameTheKey) {
  auto none = crs_from_geokeys(
      {key(1025, 2), key(2052, 9001), key(2054, 9102), key(3076, 9001), key(4099, 9001)});
  ASSERT_FALSE(none.ok());
  EXPECT_EQ(none.error().code, ErrorCode::InvalidArgument);
  EXPECT_NE(none.error().message.find("no CRS"), std::string::npos);

  // A method neither our engines nor the key mapping knows (CT_Gnomonic) is named.
  auto gnomonic = crs_from_geokeys(
      {key(1024, 1), key(2048, 4326), key(3072, 32767), key(3075, 19), key(3076, 9001)});
  ASSERT_FALSE(gnomonic.ok());
  EXPECT_EQ(gnomonic.error().code, ErrorCode::Unsupported);
  EXPECT_NE(gnomonic.error().message.find("CT_Gnomonic"), std::string::npos)
      << gnomonic.error().message;

  auto lcc = crs_from_geokeys({key(1024, 1), key(2048, 4269), key(3072, 32767), key(3075, 8),
                               key(3076, 9001), key(3078, 43.0)});
  ASSERT_FALSE(lcc.ok());
  EXPECT_NE(lcc.error().message.find("3079"), std::string::npos);

  auto geocentric = crs_from_geokeys({key(1024, 3)});
  ASSERT_FALSE(geocentric.ok());
  EXPECT_EQ(geocentric.error().code, ErrorCode::Unsupported);

  // A projected code whose method PROJ computes for us (Swiss oblique Mercator).
  auto swiss = crs_from_geokeys({key(1024, 1), key(3072, 2056)});
  ASSERT_TRUE(swiss.ok()) << swiss.error().message;
  EXPECT_NE(swiss.value().projection->method_name.find("Oblique Mercator"), std::string::npos);
  auto unknown = crs_from_geokeys({key(1024, 1), key(3072, 65000)});
  ASSERT_FALSE(unknown.ok());
  EXPECT_NE(unknown.error().message.find("65000"), std::string::npos);

  auto bad_value = crs_from_geokeys({GeoKeyEntry{1024, {}, "oops"}});
  ASSERT_FALSE(bad_value.ok());
  EXPECT_NE(bad_value.error().message.find("1024"), std::string::npos);
}

TEST(CrsGeoKeys, UtmProjectionCodeWithUserDefinedPcs) {
  auto crs = crs_from_geokeys(
      {key(1024, 1), key(2048, 4269), key(3072, 32767), key(3074, 16010), key(3076, 9001)});
  ASSERT_TRUE(crs.ok()) << crs.error().message;
  EXPECT_EQ(crs_difference(crs.value(), crs_from_epsg(26910).value()), std::nullopt);
}

// ---- the shared LAS files ----------------------------------------------------------------

TEST(CrsSharedFiles, AutzenKeysAndWktAgree) {
  SHARED_FILE(file, "pdal/autzen_trim.las");
  ASSERT_TRUE(file->geokeys && file->wkt);
  CrsCandidates c;
  c.geokeys = crs_from_geokeys(*file->geokeys);
  c.wkt = crs_from_wkt(*file->wkt);
  ASSERT_TRUE(c.geokeys->ok()) << c.geokeys->error().message;
  ASSERT_TRUE(c.wkt->ok()) << c.wkt->error().message;
  auto crs = reconcile_crs(c);
  ASSERT_TRUE(crs.ok());
  EXPECT_FALSE(mentions(crs.value().warnings, "disagree")) << all(crs.value().warnings);
  EXPECT_EQ(crs_difference(crs.value(), crs_from_epsg(2994).value()), std::nullopt);
}

TEST(CrsSharedFiles, InterestingLasKeysDisagreeWithItsWkt) {
  // pdal/interesting.las: ESRI wrote the false easting in metres (399999.99...) under a
  // feet unit; per GeoTIFF the keys mean 121920 m. Its WKT says 1312335.958 ft = 400 km.
  SHARED_FILE(file, "pdal/interesting.las");
  CrsCandidates c;
  c.geokeys = crs_from_geokeys(*file->geokeys);
  c.wkt = crs_from_wkt(*file->wkt);
  ASSERT_TRUE(c.geokeys->ok() && c.wkt->ok());
  EXPECT_NEAR(param(c.geokeys->value(), "x_0"), 121920.0, 1e-3);
  EXPECT_NEAR(param(c.wkt->value(), "x_0"), 400000.0, 1e-3);
  auto crs = reconcile_crs(c);
  ASSERT_TRUE(crs.ok());
  EXPECT_NEAR(param(crs.value(), "x_0"), 400000.0, 1e-3);  // WKT wins
  ASSERT_TRUE(mentions(crs.value().warnings, "GeoTIFF keys")) << all(crs.value().warnings);
  EXPECT_TRUE(mentions(crs.value().warnings, "projection")) << all(crs.value().warnings);
  EXPECT_TRUE(mentions(crs.value().warnings, "using WKT")) << all(crs.value().warnings);
}

TEST(CrsSharedFiles, KeysOfTheFormatCaseFiles) {
  struct Case {
    const char* file;
    int epsg;
    int vertical;
  };
  for (const Case& c :
       {Case{"pdal/autzen-utm.las", 26910, 0}, Case{"pdal/permutations_1.2_0.las", 26915, 0},
        Case{"liblas/srs_vertcs.las", 32617, 5703}, Case{"las-rs/32-1-472-150-76.las", 25832, 5941},
        Case{"pdal/bad-geotiff-keys.las", 32617, 0},
        Case{"liblas/certainty3d-color-utm-feet-navd88.las", 2229, 0},
        Case{"pdal/epsg_4326.las", 4326, 0}, Case{"pdal/autzen-dd.las", 4326, 0}}) {
    auto file = shared_file(c.file);
    if (!file) GTEST_SKIP() << "../shared/data not present";
    ASSERT_TRUE(file->geokeys.has_value()) << c.file;
    auto crs = crs_from_geokeys(*file->geokeys);
    ASSERT_TRUE(crs.ok()) << c.file << ": " << crs.error().message;
    EXPECT_EQ(crs.value().epsg, c.epsg) << c.file;
    if (c.vertical) {
      ASSERT_TRUE(crs.value().vertical.has_value()) << c.file;
      EXPECT_EQ(crs.value().vertical->epsg, c.vertical) << c.file;
    }
    EXPECT_EQ(crs_difference(crs.value(), crs_from_epsg(c.epsg).value()), std::nullopt) << c.file;
  }
  SHARED_FILE(feet, "liblas/certainty3d-color-utm-feet-navd88.las");
  EXPECT_DOUBLE_EQ(crs_from_geokeys(*feet->geokeys).value().z_unit_metres(), 1200.0 / 3937.0);
  SHARED_FILE(mvk, "pdal/mvk-thin.las");
  auto mvk_crs = crs_from_geokeys(*mvk->geokeys);
  ASSERT_TRUE(mvk_crs.ok());
  EXPECT_NEAR(param(mvk_crs.value(), "x_0"), 700000.0, 1e-6);
  SHARED_FILE(empty, "pdal/1.2-empty-geotiff-vlrs.las");
  auto none = crs_from_geokeys(*empty->geokeys);
  ASSERT_FALSE(none.ok());
  EXPECT_NE(none.error().message.find("no CRS"), std::string::npos);
}

TEST(CrsSharedFiles, WktOfTheFormatCaseFiles) {
  SHARED_FILE(nm, "pdal/test1_4.las");
  auto crs = crs_from_wkt(*nm->wkt);
  ASSERT_TRUE(crs.ok()) << crs.error().message;
  EXPECT_EQ(crs.value().epsg, 2903);
  EXPECT_EQ(crs_difference(crs.value(), crs_from_epsg(2903).value()), std::nullopt);
  // Its VERTCS nested inside the PROJCS is no WKT PROJ reads (dropped): z keeps the
  // horizontal unit, the US survey foot, as the LAS convention says.
  EXPECT_DOUBLE_EQ(crs.value().z_unit_metres(), 1200.0 / 3937.0);

  SHARED_FILE(w3, "pdal/wontcompress3.las");
  auto utm = crs_from_wkt(*w3->wkt);
  ASSERT_TRUE(utm.ok());
  EXPECT_EQ(crs_difference(utm.value(), crs_from_epsg(26919).value()), std::nullopt);

  SHARED_FILE(evlr, "laspy/simple1_4.las");
  ASSERT_TRUE(evlr->wkt.has_value());
  auto geographic = crs_from_wkt(*evlr->wkt);
  ASSERT_TRUE(geographic.ok()) << geographic.error().message;
  EXPECT_EQ(geographic.value().kind, CrsKind::Geographic);
  EXPECT_EQ(crs_difference(geographic.value(), crs_from_epsg(4326).value()), std::nullopt);

  SHARED_FILE(warsaw, "pdal/warsaw_small.las");
  auto empty = crs_from_wkt(*warsaw->wkt);  // a 3-byte record, "''" and a NUL
  ASSERT_FALSE(empty.ok());
  EXPECT_NE(empty.error().message.find("WKT"), std::string::npos) << empty.error().message;
}

// ---- WKT ---------------------------------------------------------------------------------

const char* kRdNapWkt2 =
    R"wkt(COMPOUNDCRS["Amersfoort / RD New + NAP height",PROJCRS["Amersfoort / RD New",BASEGEOGCRS["Amersfoort",DATUM["Amersfoort",ELLIPSOID["Bessel 1841",6377397.155,299.1528128,LENGTHUNIT["metre",1]]],PRIMEM["Greenwich",0,ANGLEUNIT["degree",0.0174532925199433]],ID["EPSG",4289]],CONVERSION["RD New",METHOD["Oblique Stereographic",ID["EPSG",9809]],PARAMETER["Latitude of natural origin",52.1561605555556,ANGLEUNIT["degree",0.0174532925199433],ID["EPSG",8801]],PARAMETER["Longitude of natural origin",5.38763888888889,ANGLEUNIT["degree",0.0174532925199433],ID["EPSG",8802]],PARAMETER["Scale factor at natural origin",0.9999079,SCALEUNIT["unity",1],ID["EPSG",8805]],PARAMETER["False easting",155000,LENGTHUNIT["metre",1],ID["EPSG",8806]],PARAMETER["False northing",463000,LENGTHUNIT["metre",1],ID["EPSG",8807]]],CS[Cartesian,2],AXIS["easting (X)",east,ORDER[1],LENGTHUNIT["metre",1]],AXIS["northing (Y)",north,ORDER[2],LENGTHUNIT["metre",1]]],VERTCRS["NAP height",VDATUM["Normaal Amsterdams Peil"],CS[vertical,1],AXIS["gravity-related height (H)",up,LENGTHUNIT["metre",1]]],USAGE[SCOPE["Engineering survey, topographic mapping."],AREA["Netherlands - onshore."],BBOX[50.75,3.2,53.7,7.22]],ID["EPSG",7415]])wkt";

const char* kNyBoundWkt2 =
    R"wkt(BOUNDCRS[SOURCECRS[PROJCRS["NAD83 / New York Long Island (ftUS)",BASEGEODCRS["NAD83",DATUM["North American Datum 1983",ELLIPSOID["GRS 1980",6378137,298.257222101,LENGTHUNIT["metre",1]]],PRIMEM["Greenwich",0,ANGLEUNIT["degree",0.0174532925199433]]],CONVERSION["SPCS83 New York Long Island zone (US Survey feet)",METHOD["Lambert Conic Conformal (2SP)",ID["EPSG",9802]],PARAMETER["Latitude of false origin",40.1666666666667,ANGLEUNIT["degree",0.0174532925199433],ID["EPSG",8821]],PARAMETER["Longitude of false origin",-74,ANGLEUNIT["degree",0.0174532925199433],ID["EPSG",8822]],PARAMETER["Latitude of 1st standard parallel",41.0333333333333,ANGLEUNIT["degree",0.0174532925199433],ID["EPSG",8823]],PARAMETER["Latitude of 2nd standard parallel",40.6666666666667,ANGLEUNIT["degree",0.0174532925199433],ID["EPSG",8824]],PARAMETER["Easting at false origin",984250,LENGTHUNIT["US survey foot",0.304800609601219],ID["EPSG",8826]],PARAMETER["Northing at false origin",0,LENGTHUNIT["US survey foot",0.304800609601219],ID["EPSG",8827]]],CS[Cartesian,2],AXIS["easting (X)",east,ORDER[1],LENGTHUNIT["US survey foot",0.304800609601219]],AXIS["northing (Y)",north,ORDER[2],LENGTHUNIT["US survey foot",0.304800609601219]],ID["EPSG",2263]]],TARGETCRS[GEODCRS["WGS 84",DATUM["World Geodetic System 1984",ELLIPSOID["WGS 84",6378137,298.257223563,LENGTHUNIT["metre",1]]],PRIMEM["Greenwich",0,ANGLEUNIT["degree",0.0174532925199433]],CS[ellipsoidal,2],AXIS["latitude",north,ORDER[1],ANGLEUNIT["degree",0.0174532925199433]],AXIS["longitude",east,ORDER[2],ANGLEUNIT["degree",0.0174532925199433]],ID["EPSG",4326]]],ABRIDGEDTRANSFORMATION["NAD83 to WGS 84 (1)",METHOD["Geocentric translations (geog2D domain)",ID["EPSG",9603]],PARAMETER["X-axis translation",0,ID["EPSG",8605]],PARAMETER["Y-axis translation",0,ID["EPSG",8606]],PARAMETER["Z-axis translation",0,ID["EPSG",8607]],ID["EPSG",1188]]])wkt";

TEST(CrsWkt, Wkt2CompoundAndBoundCrs) {
  auto rd = crs_from_wkt(kRdNapWkt2);
  ASSERT_TRUE(rd.ok()) << rd.error().message;
  EXPECT_EQ(crs_difference(rd.value(), crs_from_epsg(7415).value()), std::nullopt);
  ASSERT_TRUE(rd.value().vertical.has_value());
  EXPECT_EQ(rd.value().vertical->name, "NAP height");
  EXPECT_EQ(rd.value().datum.to_wgs84_source, crs_from_epsg(28992).value().datum.to_wgs84_source);

  auto ny = crs_from_wkt(kNyBoundWkt2);
  ASSERT_TRUE(ny.ok()) << ny.error().message;
  EXPECT_EQ(ny.value().epsg, 2263);
  EXPECT_EQ(ny.value().linear_unit.epsg, 9003);  // 0.304800609601219 snapped to 1200/3937
  EXPECT_EQ(crs_difference(ny.value(), crs_from_epsg(2263).value()), std::nullopt);
  EXPECT_NE(ny.value().datum.to_wgs84_source.find("TOWGS84"), std::string::npos);
}

TEST(CrsWkt, EsriAndGdalDialects) {
  struct Case {
    const char* wkt;
    int same_as;
  };
  const Case cases[] = {
      {R"wkt(PROJCS["RD_New",GEOGCS["GCS_Amersfoort",DATUM["D_Amersfoort",SPHEROID["Bessel_1841",6377397.155,299.1528128]],PRIMEM["Greenwich",0.0],UNIT["Degree",0.0174532925199433]],PROJECTION["Double_Stereographic"],PARAMETER["False_Easting",155000.0],PARAMETER["False_Northing",463000.0],PARAMETER["Central_Meridian",5.38763888888889],PARAMETER["Scale_Factor",0.9999079],PARAMETER["Latitude_Of_Origin",52.1561605555556],UNIT["Meter",1.0]])wkt",
       28992},
      {R"wkt(PROJCS["WGS_1984_Antarctic_Polar_Stereographic",GEOGCS["GCS_WGS_1984",DATUM["D_WGS_1984",SPHEROID["WGS_1984",6378137.0,298.257223563]],PRIMEM["Greenwich",0.0],UNIT["Degree",0.0174532925199433]],PROJECTION["Stereographic_South_Pole"],PARAMETER["False_Easting",0.0],PARAMETER["False_Northing",0.0],PARAMETER["Central_Meridian",0.0],PARAMETER["Standard_Parallel_1",-71.0],UNIT["Meter",1.0]])wkt",
       3031},
      {R"wkt(PROJCS["WGS 84 / NSIDC Sea Ice Polar Stereographic North",GEOGCS["WGS 84",DATUM["WGS_1984",SPHEROID["WGS 84",6378137,298.257223563,AUTHORITY["EPSG","7030"]],AUTHORITY["EPSG","6326"]],PRIMEM["Greenwich",0,AUTHORITY["EPSG","8901"]],UNIT["degree",0.0174532925199433,AUTHORITY["EPSG","9122"]],AUTHORITY["EPSG","4326"]],PROJECTION["Polar_Stereographic"],PARAMETER["latitude_of_origin",70],PARAMETER["central_meridian",-45],PARAMETER["false_easting",0],PARAMETER["false_northing",0],UNIT["metre",1,AUTHORITY["EPSG","9001"]],AUTHORITY["EPSG","3413"]])wkt",
       3413},
      {R"wkt(PROJCS["UPS_North",GEOGCS["GCS_WGS_1984",DATUM["D_WGS_1984",SPHEROID["WGS_1984",6378137.0,298.257223563]],PRIMEM["Greenwich",0.0],UNIT["Degree",0.0174532925199433]],PROJECTION["Polar_Stereographic"],PARAMETER["latitude_of_origin",90.0],PARAMETER["central_meridian",0.0],PARAMETER["scale_factor",0.994],PARAMETER["false_easting",2000000.0],PARAMETER["false_northing",2000000.0],UNIT["Meter",1.0]])wkt",
       32661},
      // Lower-case keywords, round brackets, spaces.
      {R"wkt(geogcs ( "WGS 84" , datum ( "WGS_1984" , spheroid ( "WGS 84" , 6378137 , 298.257223563 ) ) , primem ( "Greenwich" , 0 ) , unit ( "degree" , 0.0174532925199433 ) ))wkt",
       4326},
  };
  for (const Case& c : cases) {
    auto crs = crs_from_wkt(c.wkt);
    ASSERT_TRUE(crs.ok()) << c.same_as << ": " << crs.error().message;
    EXPECT_EQ(crs_difference(crs.value(), crs_from_epsg(c.same_as).value()), std::nullopt)
        << c.same_as;
  }
}

TEST(CrsWkt, Wkt1RoundTripsTheCityCodes) {
  for (int code :
       {4326, 4258, 4289, 4277, 32631, 32733, 25832, 26910, 6339, 32661, 32761, 28992, 7415,
        3031, 3413, 2193, 2157, 27700, 2154,  2991,  2992,  2263, 2227,  2236,  2903}) {
    const Crs crs = crs_from_epsg(code).value();
    const std::string wkt = crs_to_wkt1(crs);
    auto back = crs_from_wkt(wkt);
    ASSERT_TRUE(back.ok()) << code << ": " << back.error().message << "\n" << wkt;
    EXPECT_EQ(crs_difference(crs, back.value()), std::nullopt) << code << "\n" << wkt;
    EXPECT_EQ(back.value().epsg, crs.epsg) << code;
    // Only what the CRS itself warrants (no geoid grid for NAP here) is said.
    EXPECT_EQ(back.value().warnings, crs.warnings) << code << ": " << all(back.value().warnings);
  }
}

// A GeoPackage's row for the horizontal code holds the horizontal CRS alone: from the
// database by code (with its AUTHORITY), and from the definition's first component for a
// compound CRS without a code.
TEST(CrsWkt, HorizontalWkt1DropsTheVerticalPart) {
  const Crs rd_nap = crs_from_epsg(28992, 5709).value();
  ASSERT_TRUE(rd_nap.vertical.has_value());
  const std::string wkt = crs_to_horizontal_wkt1(rd_nap);
  EXPECT_EQ(wkt.rfind("PROJCS[", 0), 0u) << wkt;
  EXPECT_EQ(wkt.find("COMPD_CS"), std::string::npos) << wkt;
  EXPECT_EQ(wkt.find("NAP"), std::string::npos) << wkt;
  EXPECT_NE(wkt.find("AUTHORITY[\"EPSG\",\"28992\"]"), std::string::npos) << wkt;
  auto back = crs_from_wkt(wkt);
  ASSERT_TRUE(back.ok()) << back.error().message;
  EXPECT_EQ(back.value().epsg, 28992);
  EXPECT_FALSE(back.value().vertical.has_value());
  // The whole CRS keeps its vertical part.
  EXPECT_EQ(crs_to_wkt1(rd_nap).rfind("COMPD_CS[", 0), 0u);
  // Without a code: the compound's horizontal component, read back as the same CRS.
  Crs custom = crs_from_wkt(kRdNapWkt2).value();
  custom.epsg = 0;
  const std::string own = crs_to_horizontal_wkt1(custom);
  EXPECT_EQ(own.rfind("PROJCS[", 0), 0u) << own;
  auto again = crs_from_wkt(own);
  ASSERT_TRUE(again.ok()) << again.error().message;
  EXPECT_FALSE(again.value().vertical.has_value());
  EXPECT_EQ(again.value().epsg, 28992);  // PROJ identifies it
  // A geographic CRS is written as itself.
  EXPECT_EQ(crs_to_horizontal_wkt1(crs_from_epsg(4326).value()).rfind("GEOGCS[", 0), 0u);
}

TEST(CrsWkt, ErrorsAreNamed) {
  auto syntax = crs_from_wkt(R"wkt(PROJCS["x",GEOGCS["y")wkt");
  ASSERT_FALSE(syntax.ok());
  EXPECT_EQ(syntax.error().code, ErrorCode::InvalidArgument);
  EXPECT_NE(syntax.error().message.find("WKT"), std::string::npos);

  auto mercator = crs_from_wkt(
      R"wkt(PROJCS["WGS 84 / World Mercator",GEOGCS["WGS 84",DATUM["WGS_1984",SPHEROID["WGS 84",6378137,298.257223563]],PRIMEM["Greenwich",0],UNIT["degree",0.0174532925199433]],PROJECTION["Mercator_1SP"],PARAMETER["central_meridian",0],PARAMETER["scale_factor",1],PARAMETER["false_easting",0],PARAMETER["false_northing",0],UNIT["metre",1]])wkt");
  ASSERT_TRUE(mercator.ok()) << mercator.error().message;  // a method PROJ computes
  EXPECT_NE(mercator.value().projection->proj_string.find("+proj=merc"), std::string::npos);
  auto nonsense = crs_from_wkt(
      R"wkt(PROJCS["x",GEOGCS["WGS 84",DATUM["WGS_1984",SPHEROID["WGS 84",6378137,298.257223563]],PRIMEM["Greenwich",0],UNIT["degree",0.0174532925199433]],PROJECTION["No_Such_Projection"],UNIT["metre",1]])wkt");
  ASSERT_FALSE(nonsense.ok());
  EXPECT_EQ(nonsense.error().code, ErrorCode::Unsupported);
  EXPECT_NE(nonsense.error().message.find("No_Such_Projection"), std::string::npos);

  auto geocentric = crs_from_wkt(
      R"wkt(GEOCCS["WGS 84",DATUM["WGS_1984",SPHEROID["WGS 84",6378137,298.257223563]],UNIT["metre",1]])wkt");
  ASSERT_TRUE(geocentric.ok()) << geocentric.error().message;  // a CRS kind of its own
  EXPECT_EQ(geocentric.value().kind, CrsKind::Geocentric);

  auto vertical_only =
      crs_from_wkt(R"wkt(VERT_CS["NAVD88",VERT_DATUM["NAVD88",2005],UNIT["metre",1]])wkt");
  ASSERT_FALSE(vertical_only.ok());

  // Hostile input: deep nesting and huge text are refused without recursion blow-ups.
  std::string deep;
  for (int i = 0; i < 100000; ++i) deep += "A[";
  auto nested = crs_from_wkt(deep);
  ASSERT_FALSE(nested.ok());
  EXPECT_NE(nested.error().message.find("WKT"), std::string::npos);
  auto huge = crs_from_wkt(std::string(3 << 20, ' '));
  ASSERT_FALSE(huge.ok());
}

TEST(CrsWkt, TowgsConventionAndUnknownDatums) {
  // GDAL's EPSG:28992 WKT 1 carries EPSG:15739 in the position-vector convention.
  auto rd = crs_from_wkt(
      R"wkt(PROJCS["Amersfoort / RD New",GEOGCS["Amersfoort",DATUM["Amersfoort",SPHEROID["Bessel 1841",6377397.155,299.1528128,AUTHORITY["EPSG","7004"]],TOWGS84[565.2369,50.0087,465.658,-0.406857,0.350733,-1.87035,4.0812],AUTHORITY["EPSG","6289"]],PRIMEM["Greenwich",0],UNIT["degree",0.0174532925199433]],PROJECTION["Oblique_Stereographic"],PARAMETER["latitude_of_origin",52.15616055555555],PARAMETER["central_meridian",5.38763888888889],PARAMETER["scale_factor",0.9999079],PARAMETER["false_easting",155000],PARAMETER["false_northing",463000],UNIT["metre",1],AUTHORITY["EPSG","28992"]])wkt");
  ASSERT_TRUE(rd.ok()) << rd.error().message;
  EXPECT_DOUBLE_EQ(rd.value().datum.to_wgs84->rx_arcsec, 0.406857);
  EXPECT_DOUBLE_EQ(rd.value().datum.to_wgs84->rz_arcsec, 1.87035);
  auto diff = crs_difference(rd.value(), crs_from_epsg(28992).value());
  ASSERT_TRUE(diff.has_value());  // 15739 vs 9281
  EXPECT_NE(diff->find("datum shift"), std::string::npos);

  auto odd = crs_from_wkt(
      R"wkt(GEOGCS["odd",DATUM["D_Odd",SPHEROID["Clarke 1880",6378249.145,293.465]],PRIMEM["Greenwich",0],UNIT["Degree",0.0174532925199433]])wkt");
  ASSERT_TRUE(odd.ok());
  EXPECT_FALSE(odd.value().datum.to_wgs84.has_value());
  EXPECT_TRUE(mentions(odd.value().warnings, "TOWGS84"));
}

// Seeded mutation property: damaged WKT and random key sets return a CRS or a named error,
// never crash (the sanitizer job runs this too). A failing seed becomes a named regression.
TEST(CrsRobustness, MutatedWktAndRandomKeysNeverCrash) {
  std::mt19937_64 rng(0xC55);
  const std::string seeds[] = {kRdNapWkt2, kNyBoundWkt2,
                               crs_to_wkt1(crs_from_epsg(2992, 6360).value())};
  const char alphabet[] = "[](),\"AZaz09.-+eE_ ";
  int ok = 0;
  for (int i = 0; i < 6000; ++i) {
    std::string text = seeds[i % 3];
    const int edits = 1 + static_cast<int>(rng() % 8);
    for (int e = 0; e < edits && !text.empty(); ++e) {
      const std::size_t at = rng() % text.size();
      switch (rng() % 4) {
        case 0:
          text[at] = alphabet[rng() % (sizeof alphabet - 1)];
          break;
        case 1:
          text.erase(at, 1 + rng() % 20);
          break;
        case 2:
          text.insert(at, text.substr(rng() % text.size(), rng() % 40));
          break;
        default:
          text.resize(at);
          break;
      }
    }
    auto crs = crs_from_wkt(text);
    if (crs.ok()) {
      ++ok;
      EXPECT_TRUE(validate_crs(crs.value()).ok());
    } else {
      EXPECT_FALSE(crs.error().message.empty());
    }
  }
  EXPECT_GT(ok, 0);
  const std::uint16_t ids[] = {0,    1024, 1025, 2048, 2050, 2054, 2055, 2056, 2057,
                               2058, 2059, 2061, 2062, 3072, 3074, 3075, 3076, 3077,
                               3078, 3079, 3080, 3081, 3082, 3083, 3084, 3085, 3086,
                               3087, 3088, 3092, 3095, 4096, 4099, 5000};
  const double values[] = {
      0,    1,    2,    3,    8,  9,     15,  16,   32767,  4326,    26910,         9001, 9002,
      9003, 9102, 6326, 7030, -1, 1e308, -90, 45.5, 0.9996, 6378137, 298.257223563, 65535};
  for (int i = 0; i < 6000; ++i) {
    std::vector<GeoKeyEntry> keys;
    const int n = static_cast<int>(rng() % 12);
    for (int k = 0; k < n; ++k) {
      GeoKeyEntry e{ids[rng() % std::size(ids)], {}, {}};
      const int count = static_cast<int>(rng() % 4);
      for (int c = 0; c < count; ++c) e.numbers.push_back(values[rng() % std::size(values)]);
      if (rng() % 5 == 0) e.text = "Datum = D_North_American_1983|";
      keys.push_back(e);
    }
    auto crs = crs_from_geokeys(keys);
    if (crs.ok()) {
      EXPECT_TRUE(validate_crs(crs.value()).ok());
    }
  }
}

// ---- reconciliation, config, validation --------------------------------------------------

TEST(CrsReconcile, PrecedenceAndErrors) {
  CrsCandidates c;
  auto none = reconcile_crs(c);
  ASSERT_FALSE(none.ok());
  EXPECT_NE(none.error().message.find("no CRS"), std::string::npos);

  c.config = crs_from_config("EPSG:28992");
  auto from_config = reconcile_crs(c);
  ASSERT_TRUE(from_config.ok());
  EXPECT_EQ(from_config.value().epsg, 28992);

  c.geokeys = crs_from_epsg(32631);
  auto from_keys = reconcile_crs(c);
  ASSERT_TRUE(from_keys.ok());
  EXPECT_EQ(from_keys.value().epsg, 32631);
  EXPECT_TRUE(mentions(from_keys.value().warnings, "config")) << all(from_keys.value().warnings);

  c.config_overrides_file = true;
  auto overridden = reconcile_crs(c);
  ASSERT_TRUE(overridden.ok());
  EXPECT_EQ(overridden.value().epsg, 28992);

  CrsCandidates broken;
  broken.wkt = crs_from_wkt("PROJCS[");
  broken.geokeys = crs_from_epsg(26910);
  auto fallback = reconcile_crs(broken);
  ASSERT_TRUE(fallback.ok());
  EXPECT_TRUE(mentions(fallback.value().warnings, "WKT unreadable"))
      << all(fallback.value().warnings);

  CrsCandidates only_bad;
  only_bad.wkt = crs_from_wkt("PROJCS[");
  auto failed = reconcile_crs(only_bad);
  ASSERT_FALSE(failed.ok());
  EXPECT_NE(failed.error().message.find("WKT"), std::string::npos);
}

TEST(CrsConfig, CodesAndWkt) {
  EXPECT_EQ(crs_from_config("EPSG:28992").value().epsg, 28992);
  EXPECT_EQ(crs_from_config(" epsg:7415 ").value().vertical->epsg, 5709);
  EXPECT_EQ(crs_from_config("28992+5709").value().vertical->epsg, 5709);
  EXPECT_EQ(crs_from_config(kRdNapWkt2).value().source, "config");
  // A PROJ string with +type=crs, as the README's run.crs allows: UTM 31N on WGS 84.
  auto utm = crs_from_config("+proj=utm +zone=31 +datum=WGS84 +units=m +type=crs");
  ASSERT_TRUE(utm.ok()) << utm.error().message;
  EXPECT_EQ(utm.value().source, "config (PROJ string)");
  EXPECT_EQ(crs_difference(utm.value(), crs_from_epsg(32631).value()), std::nullopt);
  EXPECT_FALSE(crs_from_config("+proj=nonsense +type=crs").ok());
  for (const char* bad : {"", "EPSG:", "EPSG:abc", "28992+", "hello"}) {
    auto crs = crs_from_config(bad);
    EXPECT_FALSE(crs.ok()) << bad;
  }
}

TEST(CrsValidate, RangesAreChecked) {
  Crs crs = crs_from_epsg(2992).value();
  EXPECT_TRUE(validate_crs(crs).ok());
  Crs bad = crs;
  bad.projection->proj_string.clear();
  EXPECT_FALSE(validate_crs(bad).ok());
  bad = crs;
  bad.linear_unit.metres = 0;
  EXPECT_FALSE(validate_crs(bad).ok());
  bad = crs;
  bad.datum.ellipsoid.semi_major_m = std::nan("");
  EXPECT_FALSE(validate_crs(bad).ok());
  bad = crs;
  bad.datum.ellipsoid.inverse_flattening = 0.5;
  EXPECT_FALSE(validate_crs(bad).ok());
  bad = crs;
  bad.projection.reset();
  EXPECT_FALSE(validate_crs(bad).ok());
}

TEST(CrsDescribe, OneLine) {
  EXPECT_EQ(describe_crs(crs_from_epsg(2992).value()),
            "EPSG:2992 NAD83 / Oregon GIC Lambert (ft): Lambert Conic Conformal (2SP), foot");
  EXPECT_EQ(describe_crs(crs_from_epsg(7415).value()),
            "EPSG:28992 Amersfoort / RD New + NAP height: Oblique Stereographic, metre + EPSG:5709 "
            "NAP height");
}

}  // namespace
}  // namespace csgtile::geo
