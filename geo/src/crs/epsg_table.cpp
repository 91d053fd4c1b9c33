// The built-in EPSG table: the ellipsoids, datums, units and CRSs a city service meets.
//
// Values are those of the EPSG Geodetic Parameter Dataset. Parameters that EPSG gives in
// sexagesimal degrees (unit 9110) are written as degrees + minutes/60 + seconds/3600 so they
// are exact; feet-based false eastings are written in the CRS's unit as EPSG gives them and
// converted to metres here.

#include <cmath>
#include <cstdio>
#include <string>

#include "crs/crs_internal.h"

namespace csgtile::geo {
namespace detail {
namespace {

double dms(double degrees, double minutes, double seconds = 0.0) {
  const double sign = degrees < 0 ? -1.0 : 1.0;
  return sign * (std::fabs(degrees) + minutes / 60.0 + seconds / 3600.0);
}

Ellipsoid make_ellipsoid(const char* name, int epsg, double a, double rf) {
  Ellipsoid e;
  e.name = name;
  e.epsg = epsg;
  e.semi_major_m = a;
  e.inverse_flattening = rf;
  return e;
}

GeodeticDatum null_datum(const char* name, int epsg, int ellipsoid, const char* source) {
  GeodeticDatum d;
  d.name = name;
  d.epsg = epsg;
  d.ellipsoid = *ellipsoid_from_epsg(ellipsoid);
  d.to_wgs84 = Helmert7{};
  d.to_wgs84_source = source;
  return d;
}

// EPSG:9281 "Amersfoort to ETRS89 (8)": the 7-parameter similarity of RDNAPTRANS(TM)2018
// (RD Bessel → ETRS89), coordinate frame, rotations in microradians. Stated accuracy 0.25 m;
// the RDNAPTRANS correction grid that brings it to 1 mm is not applied (no grid file here).
// ETRS89 is then identified with WGS 84 (EPSG:1149, null).
GeodeticDatum amersfoort_datum() {
  GeodeticDatum d;
  d.name = "Amersfoort";
  d.epsg = 6289;
  d.ellipsoid = *ellipsoid_from_epsg(7004);
  Helmert7 h;
  h.tx_m = 565.7381;
  h.ty_m = 50.4018;
  h.tz_m = 465.2904;
  h.rx_arcsec = 1.91514 * kArcSecondsPerMicroradian;
  h.ry_arcsec = -1.60363 * kArcSecondsPerMicroradian;
  h.rz_arcsec = 9.09546 * kArcSecondsPerMicroradian;
  h.scale_ppm = 4.07244;
  d.to_wgs84 = h;
  d.to_wgs84_source =
      "EPSG:9281 Amersfoort to ETRS89 (8) (RDNAPTRANS2018 Helmert without its correction grid, "
      "0.25 m), ETRS89 = WGS 84";
  return d;
}

// EPSG:1314 "OSGB36 to WGS 84 (6)", published in the position-vector convention; 2 m.
GeodeticDatum osgb36_datum() {
  GeodeticDatum d;
  d.name = "Ordnance Survey of Great Britain 1936";
  d.epsg = 6277;
  d.ellipsoid = *ellipsoid_from_epsg(7001);
  d.to_wgs84 = helmert_from_position_vector(446.448, -125.157, 542.06, 0.15, 0.247, 0.842, -20.489);
  d.to_wgs84_source = "EPSG:1314 OSGB36 to WGS 84 (6) (Helmert, 2 m; OSTN15 not applied)";
  return d;
}

Crs geographic(int code, const char* name, int datum_code) {
  Crs c;
  c.kind = CrsKind::Geographic;
  c.name = name;
  c.epsg = code;
  c.datum = *datum_from_epsg(datum_code);
  c.angular_unit = degree_unit();
  c.source = "EPSG:" + std::to_string(code);
  return c;
}

Projection tm(double lat0, double lon0, double k0, double fe_m, double fn_m) {
  Projection p;
  p.method = ProjectionMethod::TransverseMercator;
  p.latitude_of_origin_deg = lat0;
  p.longitude_of_origin_deg = lon0;
  p.scale_factor = k0;
  p.false_easting_m = fe_m;
  p.false_northing_m = fn_m;
  return p;
}

Projection lcc2(double lat_f, double lon_f, double sp1, double sp2, double fe_m, double fn_m) {
  Projection p;
  p.method = ProjectionMethod::LambertConicConformal2SP;
  p.latitude_of_origin_deg = lat_f;
  p.longitude_of_origin_deg = lon_f;
  p.standard_parallel_1_deg = sp1;
  p.standard_parallel_2_deg = sp2;
  p.false_easting_m = fe_m;
  p.false_northing_m = fn_m;
  return p;
}

Projection polar_b(double lat_ts, double lon0) {
  Projection p;
  p.method = ProjectionMethod::PolarStereographicB;
  p.latitude_of_origin_deg = lat_ts < 0 ? -90.0 : 90.0;
  p.standard_parallel_1_deg = lat_ts;
  p.longitude_of_origin_deg = lon0;
  return p;
}

Projection ups(bool north) {
  Projection p;
  p.method = ProjectionMethod::PolarStereographicA;
  p.latitude_of_origin_deg = north ? 90.0 : -90.0;
  p.scale_factor = 0.994;
  p.false_easting_m = 2000000.0;
  p.false_northing_m = 2000000.0;
  return p;
}

Crs projected(int code, std::string name, int geographic_code, const Projection& p,
              LinearUnit unit = metre_unit()) {
  Crs c = *geographic_from_epsg(geographic_code);
  c.kind = CrsKind::Projected;
  c.name = std::move(name);
  c.epsg = code;
  c.projection = p;
  c.linear_unit = std::move(unit);
  c.source = "EPSG:" + std::to_string(code);
  return c;
}

Crs utm(int code, int zone, bool north, int geographic_code) {
  const Crs base = *geographic_from_epsg(geographic_code);
  const std::string name = base.name + " / UTM zone " + std::to_string(zone) + (north ? "N" : "S");
  return projected(code, name, geographic_code,
                   tm(0.0, -183.0 + 6.0 * zone, 0.9996, 500000.0, north ? 0.0 : 10000000.0));
}

// JGD2011 / Japan Plane Rectangular CS I-XIX: transverse Mercator, k = 0.9999, no false
// origin; the natural origins per zone as EPSG lists them (degrees, minutes).
Crs japan_plane_rectangular(int code, int zone) {
  static constexpr double kOrigins[19][4] = {
      {33, 0, 129, 30}, {33, 0, 131, 0},  {36, 0, 132, 10}, {33, 0, 133, 30}, {36, 0, 134, 20},
      {36, 0, 136, 0},  {36, 0, 137, 10}, {36, 0, 138, 30}, {36, 0, 139, 50}, {40, 0, 140, 50},
      {44, 0, 140, 15}, {44, 0, 142, 15}, {44, 0, 144, 15}, {26, 0, 142, 0},  {26, 0, 127, 30},
      {26, 0, 124, 0},  {26, 0, 131, 0},  {20, 0, 136, 0},  {26, 0, 154, 0}};
  static const char* const kRoman[19] = {"I",    "II",  "III",  "IV",    "V",   "VI",   "VII",
                                         "VIII", "IX",  "X",    "XI",    "XII", "XIII", "XIV",
                                         "XV",   "XVI", "XVII", "XVIII", "XIX"};
  const auto& o = kOrigins[zone - 1];
  return projected(code, std::string("JGD2011 / Japan Plane Rectangular CS ") + kRoman[zone - 1],
                   6668, tm(dms(o[0], o[1]), dms(o[2], o[3]), 0.9999, 0, 0));
}

std::optional<Crs> projected_from_epsg(int code) {
  const double ft = international_foot_unit().metres;
  const double us_ft = us_survey_foot_unit().metres;
  if (code >= 32601 && code <= 32660) return utm(code, code - 32600, true, 4326);
  if (code >= 32701 && code <= 32760) return utm(code, code - 32700, false, 4326);
  if (code >= 25828 && code <= 25838) return utm(code, code - 25800, true, 4258);
  if (code >= 26901 && code <= 26923) return utm(code, code - 26900, true, 4269);
  if (code >= 6330 && code <= 6348) return utm(code, code - 6329, true, 6318);
  if (code == 6328 || code == 6329) return utm(code, code - 6328 + 59, true, 6318);
  if (code >= 6669 && code <= 6687) return japan_plane_rectangular(code, code - 6668);
  switch (code) {
    case 32661:
      return projected(code, "WGS 84 / UPS North (N,E)", 4326, ups(true));
    case 32761:
      return projected(code, "WGS 84 / UPS South (N,E)", 4326, ups(false));
    case 5041:
      return projected(code, "WGS 84 / UPS North (E,N)", 4326, ups(true));
    case 5042:
      return projected(code, "WGS 84 / UPS South (E,N)", 4326, ups(false));
    case 28992: {
      Projection p;
      p.method = ProjectionMethod::ObliqueStereographic;
      p.latitude_of_origin_deg = dms(52, 9, 22.178);
      p.longitude_of_origin_deg = dms(5, 23, 15.5);
      p.scale_factor = 0.9999079;
      p.false_easting_m = 155000.0;
      p.false_northing_m = 463000.0;
      return projected(code, "Amersfoort / RD New", 4289, p);
    }
    case 3031:
      return projected(code, "WGS 84 / Antarctic Polar Stereographic", 4326, polar_b(-71, 0));
    case 3413:
      return projected(code, "WGS 84 / NSIDC Sea Ice Polar Stereographic North", 4326,
                       polar_b(70, -45));
    case 3976:
      return projected(code, "WGS 84 / NSIDC Sea Ice Polar Stereographic South", 4326,
                       polar_b(-70, 0));
    case 3995:
      return projected(code, "WGS 84 / Arctic Polar Stereographic", 4326, polar_b(71, 0));
    case 2193:
      return projected(code, "NZGD2000 / New Zealand Transverse Mercator 2000", 4167,
                       tm(0, 173, 0.9996, 1600000, 10000000));
    case 2157:
      return projected(code, "IRENET95 / Irish Transverse Mercator", 4173,
                       tm(53.5, -8, 0.99982, 600000, 750000));
    case 27700:
      return projected(code, "OSGB36 / British National Grid", 4277,
                       tm(49, -2, 0.9996012717, 400000, -100000));
    case 2154:
      return projected(code, "RGF93 v1 / Lambert-93", 4171, lcc2(46.5, 3, 49, 44, 700000, 6600000));
    case 2991:
      return projected(code, "NAD83 / Oregon LCC (m)", 4269,
                       lcc2(41.75, -120.5, 43, 45.5, 400000, 0));
    case 2992:
      return projected(code, "NAD83 / Oregon GIC Lambert (ft)", 4269,
                       lcc2(41.75, -120.5, 43, 45.5, 1312335.958 * ft, 0),
                       international_foot_unit());
    case 2994:
      return projected(code, "NAD83(HARN) / Oregon GIC Lambert (ft)", 4152,
                       lcc2(41.75, -120.5, 43, 45.5, 1312335.958 * ft, 0),
                       international_foot_unit());
    case 2269:
    case 2913:
      return projected(
          code, code == 2269 ? "NAD83 / Oregon North (ft)" : "NAD83(HARN) / Oregon North (ft)",
          code == 2269 ? 4269 : 4152,
          lcc2(dms(43, 40), -120.5, 46, dms(44, 20), 8202099.738 * ft, 0),
          international_foot_unit());
    case 2270:
      return projected(code, "NAD83 / Oregon South (ft)", 4269,
                       lcc2(dms(41, 40), -120.5, 44, dms(42, 20), 4921259.843 * ft, 0),
                       international_foot_unit());
    case 2227:
      return projected(
          code, "NAD83 / California zone 3 (ftUS)", 4269,
          lcc2(36.5, -120.5, dms(38, 26), dms(37, 4), 6561666.667 * us_ft, 1640416.667 * us_ft),
          us_survey_foot_unit());
    case 2229:
      return projected(
          code, "NAD83 / California zone 5 (ftUS)", 4269,
          lcc2(33.5, -118, dms(35, 28), dms(34, 2), 6561666.667 * us_ft, 1640416.667 * us_ft),
          us_survey_foot_unit());
    case 2263:
      return projected(code, "NAD83 / New York Long Island (ftUS)", 4269,
                       lcc2(dms(40, 10), -74, dms(41, 2), dms(40, 40), 984250 * us_ft, 0),
                       us_survey_foot_unit());
    case 2236:
      return projected(code, "NAD83 / Florida East (ftUS)", 4269,
                       tm(dms(24, 20), -81, 0.999941177, 656166.667 * us_ft, 0),
                       us_survey_foot_unit());
    case 6580:
      return projected(code, "NAD83(2011) / Texas Centric Lambert Conformal", 6318,
                       lcc2(18, -100, 27.5, 35, 1500000, 5000000));
    case 2903:
      return projected(code, "NAD83(HARN) / New Mexico Central (ftUS)", 4152,
                       tm(31, -106.25, 0.9999, 1640416.667 * us_ft, 0), us_survey_foot_unit());
    default:
      return std::nullopt;
  }
}

}  // namespace

std::optional<Ellipsoid> ellipsoid_from_epsg(int code) {
  switch (code) {
    case 7030:
      return make_ellipsoid("WGS 84", 7030, 6378137.0, 298.257223563);
    case 7019:
      return make_ellipsoid("GRS 1980", 7019, 6378137.0, 298.257222101);
    case 7004:
      return make_ellipsoid("Bessel 1841", 7004, 6377397.155, 299.1528128);
    case 7001:
      return make_ellipsoid("Airy 1830", 7001, 6377563.396, 299.3249646);
    case 7008:
      return make_ellipsoid("Clarke 1866", 7008, 6378206.4, 294.978698213898);
    case 7022:
      return make_ellipsoid("International 1924", 7022, 6378388.0, 297.0);
    case 7024:
      return make_ellipsoid("Krassowsky 1940", 7024, 6378245.0, 298.3);
    case 7043:
      return make_ellipsoid("WGS 72", 7043, 6378135.0, 298.26);
    default:
      return std::nullopt;
  }
}

std::optional<GeodeticDatum> datum_from_epsg(int code) {
  switch (code) {
    case 6326:
      return null_datum("World Geodetic System 1984", 6326, 7030, "identity");
    case 6258:
      return null_datum("European Terrestrial Reference System 1989", 6258, 7019,
                        "EPSG:1149 ETRS89 to WGS 84 (1) (null, 1 m)");
    case 6269:
      return null_datum("North American Datum 1983", 6269, 7019,
                        "EPSG:1188 NAD83 to WGS 84 (1) (null, 4 m)");
    case 6152:
      return null_datum("NAD83 (High Accuracy Reference Network)", 6152, 7019,
                        "EPSG:1580 NAD83(HARN) to WGS 84 (1) (null, 2 m)");
    case 1116:
      return null_datum("NAD83 (National Spatial Reference System 2011)", 1116, 7019,
                        "EPSG:9774 NAD83(2011) to WGS 84 (1) (null, 2 m)");
    case 6167:
      return null_datum("New Zealand Geodetic Datum 2000", 6167, 7019,
                        "EPSG:1565 NZGD2000 to WGS 84 (1) (null, 1 m)");
    case 6171:
      return null_datum("Reseau Geodesique Francais 1993 v1", 6171, 7019,
                        "EPSG:1671 RGF93 v1 to WGS 84 (1) (null, 1 m)");
    case 1128:
      return null_datum("Japanese Geodetic Datum 2011", 1128, 7019,
                        "JGD2011 to WGS 84 (null, 1 m)");
    case 6173:
      return null_datum("IRENET95", 6173, 7019, "EPSG:1678 IRENET95 to WGS 84 (1) (null, 1 m)");
    case 6289:
      return amersfoort_datum();
    case 6277:
      return osgb36_datum();
    case 6267: {
      GeodeticDatum d;
      d.name = "North American Datum 1927";
      d.epsg = 6267;
      d.ellipsoid = *ellipsoid_from_epsg(7008);
      d.to_wgs84 = std::nullopt;  // needs NADCON grids: a Helmert would be 10-20 m off
      d.to_wgs84_source = "unknown (NAD27 needs NADCON grids)";
      return d;
    }
    default:
      return std::nullopt;
  }
}

std::optional<GeodeticDatum> datum_from_name(std::string_view name) {
  const std::string n = normalise_name(name);
  auto has = [&](const char* s) { return n.find(s) != std::string::npos; };
  if (n.empty()) return std::nullopt;
  if (has("wgs84") || has("wgs1984") || has("worldgeodeticsystem1984"))
    return datum_from_epsg(6326);
  if (has("etrs89") || has("europeanterrestrialreferencesystem1989") || has("etrf")) {
    return datum_from_epsg(6258);
  }
  if (has("harn") || has("highaccuracy")) return datum_from_epsg(6152);
  if (has("nad832011") || has("nsrs2011")) return datum_from_epsg(1116);
  if (has("nad83") || has("northamerican1983") || has("northamericandatum1983")) {
    return datum_from_epsg(6269);
  }
  if (has("nad27") || has("northamerican1927") || has("northamericandatum1927")) {
    return datum_from_epsg(6267);
  }
  if (has("amersfoort")) return datum_from_epsg(6289);
  if (has("jgd2011") || has("japanesegeodeticdatum2011")) return datum_from_epsg(1128);
  if (has("osgb1936") || has("osgb36") || has("ordnancesurveyofgreatbritain1936")) {
    return datum_from_epsg(6277);
  }
  if (has("nzgd2000") || has("newzealandgeodeticdatum2000")) return datum_from_epsg(6167);
  if (has("rgf93") || has("reseaugeodesiquefrancais1993")) return datum_from_epsg(6171);
  if (has("irenet95")) return datum_from_epsg(6173);
  return std::nullopt;
}

std::optional<LinearUnit> linear_unit_from_epsg(int code) {
  switch (code) {
    case 9001:
      return metre_unit();
    case 9002:
      return international_foot_unit();
    case 9003:
      return us_survey_foot_unit();
    case 9036:
      return LinearUnit{"kilometre", 1000.0, 9036};
    default:
      return std::nullopt;
  }
}

std::optional<LinearUnit> linear_unit_from_name(std::string_view name) {
  const std::string n = normalise_name(name);
  if (n == "metre" || n == "meter" || n == "metres" || n == "meters" || n == "m")
    return metre_unit();
  if (n == "ussurveyfoot" || n == "footus" || n == "ftus" || n == "usfoot" || n == "ussurveyfeet" ||
      n == "usft" || n == "surveyfoot") {
    return us_survey_foot_unit();
  }
  if (n == "foot" || n == "feet" || n == "ft" || n == "internationalfoot" || n == "footintl" ||
      n == "intlfoot") {
    return international_foot_unit();
  }
  if (n == "kilometre" || n == "kilometer" || n == "km") return linear_unit_from_epsg(9036);
  return std::nullopt;
}

std::optional<AngularUnit> angular_unit_from_epsg(int code) {
  switch (code) {
    case 9102:
    case 9122:
    case 9110:  // sexagesimal DMS as a storage unit: GeoTIFF writers mean degrees
      return degree_unit();
    case 9101:
      return AngularUnit{"radian", 1.0, 9101};
    case 9105:
      return AngularUnit{"grad", kPi / 200.0, 9105};
    case 9104:
      return AngularUnit{"arc-second", kPi / 648000.0, 9104};
    default:
      return std::nullopt;
  }
}

std::optional<AngularUnit> angular_unit_from_name(std::string_view name) {
  const std::string n = normalise_name(name);
  if (n == "degree" || n == "degrees" || n == "deg") return degree_unit();
  if (n == "radian" || n == "radians" || n == "rad") return angular_unit_from_epsg(9101);
  if (n == "grad" || n == "gon" || n == "grads") return angular_unit_from_epsg(9105);
  if (n == "arcsecond" || n == "arcseconds") return angular_unit_from_epsg(9104);
  return std::nullopt;
}

LinearUnit linear_unit_from_size(std::string name, double metres) {
  for (const LinearUnit& known : {metre_unit(), international_foot_unit(), us_survey_foot_unit()}) {
    if (std::fabs(metres - known.metres) <= 1e-12 * known.metres) return known;
  }
  return LinearUnit{std::move(name), metres, 0};
}

AngularUnit angular_unit_from_size(std::string name, double radians) {
  for (int code : {9102, 9101, 9105}) {
    const AngularUnit known = *angular_unit_from_epsg(code);
    if (std::fabs(radians - known.radians) <= 1e-12 * known.radians) return known;
  }
  return AngularUnit{std::move(name), radians, 0};
}

std::optional<VerticalCrs> vertical_from_epsg(int code) {
  auto make = [code](const char* name, LinearUnit unit) {
    return VerticalCrs{code, name, std::move(unit)};
  };
  switch (code) {
    case 5703:
      return make("NAVD88 height", metre_unit());
    case 6360:
      return make("NAVD88 height (ftUS)", us_survey_foot_unit());
    case 8228:
      return make("NAVD88 height (ft)", international_foot_unit());
    case 5709:
      return make("NAP height", metre_unit());
    case 5941:
      return make("NN2000 height", metre_unit());
    case 5773:
      return make("EGM96 height", metre_unit());
    case 3855:
      return make("EGM2008 height", metre_unit());
    case 7837:
      return make("DHHN2016 height", metre_unit());
    case 5701:
      return make("ODN height", metre_unit());
    case 5714:
      return make("MSL height", metre_unit());
    default:
      return std::nullopt;
  }
}

std::optional<Crs> geographic_from_epsg(int code) {
  switch (code) {
    case 4326:
      return geographic(code, "WGS 84", 6326);
    case 4979:
      return geographic(code, "WGS 84", 6326);
    case 4258:
      return geographic(code, "ETRS89", 6258);
    case 4937:
      return geographic(code, "ETRS89", 6258);
    case 4269:
      return geographic(code, "NAD83", 6269);
    case 4152:
      return geographic(code, "NAD83(HARN)", 6152);
    case 6318:
      return geographic(code, "NAD83(2011)", 1116);
    case 4289:
      return geographic(code, "Amersfoort", 6289);
    case 4167:
      return geographic(code, "NZGD2000", 6167);
    case 6668:
      return geographic(code, "JGD2011", 1128);
    case 4171:
      return geographic(code, "RGF93 v1", 6171);
    case 4173:
      return geographic(code, "IRENET95", 6173);
    case 4277:
      return geographic(code, "OSGB36", 6277);
    case 4267:
      return geographic(code, "NAD27", 6267);
    default:
      return std::nullopt;
  }
}

Helmert7 helmert_from_position_vector(double tx, double ty, double tz, double rx, double ry,
                                      double rz, double ppm) {
  // The two conventions differ only in the sign of the rotations (EPSG GN 7-2 §4.3.3).
  Helmert7 h;
  h.tx_m = tx;
  h.ty_m = ty;
  h.tz_m = tz;
  h.rx_arcsec = -rx;
  h.ry_arcsec = -ry;
  h.rz_arcsec = -rz;
  h.scale_ppm = ppm;
  return h;
}

std::string normalise_name(std::string_view name) {
  std::string out;
  out.reserve(name.size());
  for (char ch : name) {
    if (ch >= 'A' && ch <= 'Z')
      out.push_back(static_cast<char>(ch - 'A' + 'a'));
    else if ((ch >= 'a' && ch <= 'z') || (ch >= '0' && ch <= '9'))
      out.push_back(ch);
  }
  return out;
}

bool is_wgs84_ellipsoid(const Ellipsoid& e) {
  return e.semi_major_m == 6378137.0 && std::fabs(e.inverse_flattening - 298.257223563) < 1e-9;
}

bool is_utm(const Projection& p, int* zone, bool* north) {
  if (p.method != ProjectionMethod::TransverseMercator) return false;
  if (p.latitude_of_origin_deg != 0.0 || p.scale_factor != 0.9996 ||
      p.false_easting_m != 500000.0) {
    return false;
  }
  if (p.false_northing_m != 0.0 && p.false_northing_m != 10000000.0) return false;
  const double z = (p.longitude_of_origin_deg + 183.0) / 6.0;
  const double rounded = std::round(z);
  if (std::fabs(z - rounded) > 1e-12 || rounded < 1 || rounded > 60) return false;
  *zone = static_cast<int>(rounded);
  *north = p.false_northing_m == 0.0;
  return true;
}

bool is_ups(const Projection& p, bool* north) {
  if (p.method != ProjectionMethod::PolarStereographicA) return false;
  if (std::fabs(p.latitude_of_origin_deg) != 90.0 || p.longitude_of_origin_deg != 0.0 ||
      p.scale_factor != 0.994 || p.false_easting_m != 2000000.0 ||
      p.false_northing_m != 2000000.0) {
    return false;
  }
  *north = p.latitude_of_origin_deg > 0;
  return true;
}

std::string format_number(double v) {
  char buffer[40];
  std::snprintf(buffer, sizeof buffer, "%.17g", v);
  // Prefer the shortest representation that round-trips.
  for (int precision = 6; precision < 17; ++precision) {
    char shorter[40];
    std::snprintf(shorter, sizeof shorter, "%.*g", precision, v);
    if (std::strtod(shorter, nullptr) == v) return shorter;
  }
  return buffer;
}

}  // namespace detail

kernel::Result<Crs> crs_from_epsg(int code, int vertical_epsg) {
  std::optional<Crs> crs;
  if (code == 7415) {  // Amersfoort / RD New + NAP height
    crs = detail::projected_from_epsg(28992);
    crs->name = "Amersfoort / RD New + NAP height";
    crs->source = "EPSG:7415";
    if (vertical_epsg == 0) vertical_epsg = 5709;
  } else {
    crs = detail::geographic_from_epsg(code);
    if (!crs) crs = detail::projected_from_epsg(code);
  }
  if (!crs) {
    // Beyond the table: PROJ's database, as WKT 1 through the WKT reader.
    auto from_proj = detail::crs_from_proj_database(code);
    if (!from_proj.ok()) return from_proj.error();
    crs = std::move(from_proj).value();
  }
  if (vertical_epsg != 0) {
    if (auto v = detail::vertical_from_epsg(vertical_epsg)) {
      crs->vertical = *v;
    } else if (auto p = detail::vertical_from_proj_database(vertical_epsg)) {
      crs->vertical = *p;
    } else {
      crs->vertical =
          VerticalCrs{vertical_epsg, "EPSG:" + std::to_string(vertical_epsg), metre_unit()};
      crs->warnings.push_back("vertical CRS EPSG:" + std::to_string(vertical_epsg) +
                              " is neither in the built-in table nor a vertical CRS of PROJ's "
                              "database: its unit is assumed to be metre");
    }
  }
  if (auto status = validate_crs(*crs); !status.ok()) {
    return kernel::Error{status.error().code, "EPSG:" + std::to_string(code) + "+" +
                                                  std::to_string(vertical_epsg) + ": " +
                                                  status.error().message};
  }
  return *std::move(crs);
}

}  // namespace csgtile::geo
