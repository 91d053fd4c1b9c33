// The CRS model's small functions: the builders' entry points (every one reads through PROJ,
// proj_model.cpp), units, validation, comparison, reconciliation, text.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>

#include "crs/crs_internal.h"
#include "crs/geodesy.h"

namespace csgtile::geo {

using kernel::Error;
using kernel::ErrorCode;
using kernel::Result;
using kernel::Status;

bool Helmert7::is_null() const {
  return tx_m == 0 && ty_m == 0 && tz_m == 0 && rx_arcsec == 0 && ry_arcsec == 0 &&
         rz_arcsec == 0 && scale_ppm == 0;
}

LinearUnit metre_unit() { return LinearUnit{"metre", 1.0, 9001}; }
LinearUnit international_foot_unit() { return LinearUnit{"foot", 0.3048, 9002}; }
LinearUnit us_survey_foot_unit() { return LinearUnit{"US survey foot", 1200.0 / 3937.0, 9003}; }
AngularUnit degree_unit() { return AngularUnit{"degree", detail::kDegree, 9102}; }

double Crs::z_unit_metres() const {
  if (kind == CrsKind::Geocentric) return linear_unit.metres;
  if (vertical) return vertical->unit.metres;
  if (kind == CrsKind::Projected) return linear_unit.metres;
  return 1.0;
}

namespace {

bool finite_all(std::initializer_list<double> values) {
  for (double v : values) {
    if (!std::isfinite(v)) return false;
  }
  return true;
}

Status invalid(std::string message) {
  return Status(ErrorCode::InvalidArgument, std::move(message));
}

}  // namespace

Status validate_crs(const Crs& crs) {
  const Ellipsoid& e = crs.datum.ellipsoid;
  if (!finite_all({e.semi_major_m, e.inverse_flattening}) || e.semi_major_m <= 0) {
    return invalid("ellipsoid '" + e.name + "': semi-major axis must be positive and finite");
  }
  if (e.inverse_flattening != 0.0 && e.inverse_flattening <= 1.0) {
    return invalid("ellipsoid '" + e.name +
                   "': inverse flattening must be 0 (sphere) or > 1, got " +
                   detail::format_number(e.inverse_flattening));
  }
  if (!std::isfinite(crs.datum.prime_meridian_deg) ||
      std::fabs(crs.datum.prime_meridian_deg) > 180) {
    return invalid("prime meridian must be within ±180 degrees");
  }
  if (crs.datum.to_wgs84) {
    const Helmert7& h = *crs.datum.to_wgs84;
    if (!finite_all({h.tx_m, h.ty_m, h.tz_m, h.rx_arcsec, h.ry_arcsec, h.rz_arcsec, h.scale_ppm})) {
      return invalid("datum '" + crs.datum.name + "': non-finite Helmert parameter");
    }
  }
  if (!(crs.angular_unit.radians > 0) || !std::isfinite(crs.angular_unit.radians)) {
    return invalid("angular unit '" + crs.angular_unit.name + "' must have a positive size");
  }
  if (!(crs.linear_unit.metres > 0) || !std::isfinite(crs.linear_unit.metres)) {
    return invalid("linear unit '" + crs.linear_unit.name + "' must have a positive size");
  }
  if (crs.vertical &&
      (!(crs.vertical->unit.metres > 0) || !std::isfinite(crs.vertical->unit.metres))) {
    return invalid("vertical unit '" + crs.vertical->unit.name + "' must have a positive size");
  }
  if (crs.kind != CrsKind::Projected) {
    if (crs.projection) return invalid("a geographic or geocentric CRS has no projection");
    if (crs.kind == CrsKind::Geocentric && crs.vertical) {
      return invalid("a geocentric CRS has no vertical CRS (z is geocentric)");
    }
    return Status();
  }
  if (!crs.projection) return invalid("projected CRS '" + crs.name + "' has no projection");
  if (crs.projection->proj_string.empty()) {
    return invalid(crs.projection->method_name + ": no PROJ definition");
  }
  return Status();
}

namespace {

bool close_rel(double a, double b, double rel) {
  return std::fabs(a - b) <= rel * std::max(std::fabs(a), std::fabs(b));
}

std::string both(const char* what, const std::string& a, const std::string& b) {
  return std::string(what) + " differs: " + a + " vs " + b;
}

std::string num(double v) { return detail::format_number(v); }

const char* kind_name(CrsKind kind) {
  switch (kind) {
    case CrsKind::Geographic:
      return "geographic";
    case CrsKind::Projected:
      return "projected";
    case CrsKind::Geocentric:
      return "geocentric";
  }
  return "?";
}

std::string method_label(const Projection& p) {
  return p.method_name.empty() ? std::string("PROJ projection") : p.method_name;
}

// Where two projections are compared: around the first one's origin (its +lat_0 / +lon_0, a
// UTM zone's central meridian), clamped away from the poles.
std::vector<GeodeticPoint> sample_points(const Projection& p) {
  using detail::proj_parameter;
  double lat0 = proj_parameter(p.proj_string, "lat_0")
                    .value_or(proj_parameter(p.proj_string, "lat_1").value_or(0.0));
  double lon0 = proj_parameter(p.proj_string, "lon_0")
                    .value_or(proj_parameter(p.proj_string, "lonc").value_or(0.0));
  if (auto zone = proj_parameter(p.proj_string, "zone")) lon0 = -183.0 + 6.0 * *zone;
  if (auto ts = proj_parameter(p.proj_string, "lat_ts"); ts && std::fabs(lat0) == 90.0) lat0 = *ts;
  lat0 = std::clamp(lat0, -85.0, 85.0);
  std::vector<GeodeticPoint> points;
  for (double dlat : {-0.5, 0.0, 0.5}) {
    for (double dlon : {-0.5, 0.0, 0.5}) points.push_back({lat0 + dlat, lon0 + dlon, 0.0});
  }
  return points;
}

// nullopt when both projections give the same coordinates (0.5 mm) at the sample points.
std::optional<std::string> projection_difference(const Crs& a, const Crs& b) {
  const Projection& pa = *a.projection;
  const Projection& pb = *b.projection;
  if (pa.proj_string == pb.proj_string) return std::nullopt;
  auto ma = detail::CrsMath::create(a);
  auto mb = detail::CrsMath::create(b);
  const std::string label_a = method_label(pa) + " (" + pa.proj_string + ")";
  const std::string label_b = method_label(pb) + " (" + pb.proj_string + ")";
  if (!ma.ok() || !mb.ok()) return both("projection", label_a, label_b);
  for (const GeodeticPoint& g : sample_points(pa)) {
    std::optional<kernel::Vec3> xa, xb;
    try {
      xa = ma.value()->from_geodetic(g);
    } catch (const std::exception&) {
    }
    try {
      xb = mb.value()->from_geodetic(g);
    } catch (const std::exception&) {
    }
    if (!xa && !xb) continue;
    const std::string where =
        " at latitude " + num(g.latitude_deg) + ", longitude " + num(g.longitude_deg);
    if (!xa || !xb) return both(("projection's domain" + where).c_str(), label_a, label_b);
    const double dx = xa->x() * a.linear_unit.metres - xb->x() * b.linear_unit.metres;
    const double dy = xa->y() * a.linear_unit.metres - xb->y() * b.linear_unit.metres;
    // EPSG rounds feet-based false origins to 0.001 ft (0.3 mm): compare to 0.5 mm.
    if (std::hypot(dx, dy) > 5e-4) {
      return both(("projection (" + num(std::hypot(dx, dy)) + " m apart" + where + ")").c_str(),
                  label_a, label_b);
    }
  }
  return std::nullopt;
}

}  // namespace

std::optional<std::string> crs_difference(const Crs& a, const Crs& b) {
  if (a.kind != b.kind) return both("kind", kind_name(a.kind), kind_name(b.kind));
  const Ellipsoid& ea = a.datum.ellipsoid;
  const Ellipsoid& eb = b.datum.ellipsoid;
  if (!close_rel(ea.semi_major_m, eb.semi_major_m, 1e-12)) {
    return both("ellipsoid semi-major axis", num(ea.semi_major_m), num(eb.semi_major_m));
  }
  if (!close_rel(ea.flattening(), eb.flattening(), 1e-9)) {
    return both("ellipsoid inverse flattening", num(ea.inverse_flattening),
                num(eb.inverse_flattening));
  }
  if (std::fabs(a.datum.prime_meridian_deg - b.datum.prime_meridian_deg) > 1e-11) {
    return both("prime meridian", num(a.datum.prime_meridian_deg), num(b.datum.prime_meridian_deg));
  }
  const auto& ha = a.datum.to_wgs84;
  const auto& hb = b.datum.to_wgs84;
  if (a.datum.to_wgs84_pipeline != b.datum.to_wgs84_pipeline) {
    return both(
        "datum transformation to WGS 84 (PROJ)",
        a.datum.to_wgs84_pipeline.empty() ? a.datum.to_wgs84_source : a.datum.to_wgs84_pipeline,
        b.datum.to_wgs84_pipeline.empty() ? b.datum.to_wgs84_source : b.datum.to_wgs84_pipeline);
  }
  if (ha.has_value() != hb.has_value()) {
    return both("datum shift to WGS 84", ha ? a.datum.to_wgs84_source : "unknown",
                hb ? b.datum.to_wgs84_source : "unknown");
  }
  if (ha) {
    const double d[] = {ha->tx_m - hb->tx_m,           ha->ty_m - hb->ty_m,
                        ha->tz_m - hb->tz_m,           ha->rx_arcsec - hb->rx_arcsec,
                        ha->ry_arcsec - hb->ry_arcsec, ha->rz_arcsec - hb->rz_arcsec,
                        ha->scale_ppm - hb->scale_ppm};
    for (double v : d) {
      if (std::fabs(v) > 1e-6) {
        return both("datum shift to WGS 84",
                    "(" + num(ha->tx_m) + ", " + num(ha->ty_m) + ", " + num(ha->tz_m) + " m; " +
                        num(ha->rx_arcsec) + ", " + num(ha->ry_arcsec) + ", " + num(ha->rz_arcsec) +
                        "\"; " + num(ha->scale_ppm) + " ppm)",
                    "(" + num(hb->tx_m) + ", " + num(hb->ty_m) + ", " + num(hb->tz_m) + " m; " +
                        num(hb->rx_arcsec) + ", " + num(hb->ry_arcsec) + ", " + num(hb->rz_arcsec) +
                        "\"; " + num(hb->scale_ppm) + " ppm)");
      }
    }
  }
  if (a.kind == CrsKind::Geocentric) {
    if (!close_rel(a.linear_unit.metres, b.linear_unit.metres, 1e-12)) {
      return both("linear unit", a.linear_unit.name, b.linear_unit.name);
    }
  } else if (a.kind == CrsKind::Geographic) {
    if (!close_rel(a.angular_unit.radians, b.angular_unit.radians, 1e-12)) {
      return both("angular unit", a.angular_unit.name, b.angular_unit.name);
    }
  } else {
    if (!close_rel(a.linear_unit.metres, b.linear_unit.metres, 1e-12)) {
      return both("linear unit", a.linear_unit.name + " (" + num(a.linear_unit.metres) + " m)",
                  b.linear_unit.name + " (" + num(b.linear_unit.metres) + " m)");
    }
    if (auto diff = projection_difference(a, b)) return diff;
  }
  if (a.vertical.has_value() != b.vertical.has_value()) {
    // A vertical CRS on one side only changes nothing when the z units agree.
    if (!close_rel(a.z_unit_metres(), b.z_unit_metres(), 1e-12)) {
      return both("z unit (m)", num(a.z_unit_metres()), num(b.z_unit_metres()));
    }
  } else if (a.vertical && !close_rel(a.vertical->unit.metres, b.vertical->unit.metres, 1e-12)) {
    return both("vertical unit", a.vertical->unit.name, b.vertical->unit.name);
  }
  return std::nullopt;
}

Result<Crs> reconcile_crs(const CrsCandidates& c) {
  struct Reading {
    const char* label;
    const std::optional<Result<Crs>>* value;
  };
  std::vector<Reading> order;
  if (c.config_overrides_file) order.push_back({"config", &c.config});
  order.push_back({"WKT", &c.wkt});
  order.push_back({"GeoTIFF keys", &c.geokeys});
  if (!c.config_overrides_file) order.push_back({"config", &c.config});

  const Reading* chosen = nullptr;
  for (const Reading& r : order) {
    if (r.value->has_value() && (*r.value)->ok()) {
      chosen = &r;
      break;
    }
  }
  if (!chosen) {
    for (const Reading& r : order) {
      if (r.value->has_value()) {
        const Error& e = (*r.value)->error();
        return Error{e.code, std::string(r.label) + ": " + e.message};
      }
    }
    return Error{ErrorCode::InvalidArgument,
                 "no CRS: the file has neither WKT nor GeoTIFF keys and the config gives none"};
  }
  Crs result = (*chosen->value)->value();
  const std::string chosen_name = std::string(chosen->label) + " (" + describe_crs(result) + ")";
  for (const Reading& r : order) {
    if (&r == chosen || !r.value->has_value()) continue;
    const Result<Crs>& other = **r.value;
    if (!other.ok()) {
      result.warnings.push_back(std::string(r.label) + " unreadable (" + other.error().message +
                                "); using " + chosen_name);
      continue;
    }
    if (auto diff = crs_difference(result, other.value())) {
      result.warnings.push_back(std::string(r.label) + " (" + describe_crs(other.value()) +
                                ") disagree with " + chosen_name + ": " + *diff + "; using " +
                                chosen->label);
    }
  }
  return result;
}

std::string describe_crs(const Crs& crs) {
  std::string out;
  if (crs.epsg != 0) out += "EPSG:" + std::to_string(crs.epsg) + " ";
  out += crs.name.empty() ? std::string("unnamed") : crs.name;
  if (crs.kind == CrsKind::Projected && crs.projection) {
    out += ": " + method_label(*crs.projection) + ", " + crs.linear_unit.name;
  } else if (crs.kind == CrsKind::Geocentric) {
    out += ": geocentric, " + crs.linear_unit.name;
  } else {
    out += ": geographic, " + crs.angular_unit.name;
  }
  if (crs.vertical) {
    out +=
        " + " +
        (crs.vertical->epsg ? "EPSG:" + std::to_string(crs.vertical->epsg) + " " : std::string()) +
        crs.vertical->name;
  }
  return out;
}

Result<Crs> crs_from_config(std::string_view text) {
  auto trim = [](std::string_view s) {
    while (!s.empty() &&
           (s.front() == ' ' || s.front() == '\t' || s.front() == '\n' || s.front() == '\r')) {
      s.remove_prefix(1);
    }
    while (!s.empty() &&
           (s.back() == ' ' || s.back() == '\t' || s.back() == '\n' || s.back() == '\r')) {
      s.remove_suffix(1);
    }
    return s;
  };
  std::string_view s = trim(text);
  if (s.empty()) return Error{ErrorCode::InvalidArgument, "empty CRS text in the config"};
  if (s.front() == '{' || s.front() == '+') {  // PROJJSON, or a PROJ string (+type=crs)
    const char* kind = s.front() == '{' ? "PROJJSON" : "PROJ string";
    auto crs = detail::crs_from_proj_text(s, kind);
    if (crs.ok()) crs.value().source = "config (" + std::string(kind) + ")";
    return crs;
  }
  if (s.find('[') != std::string_view::npos || s.find('(') != std::string_view::npos) {
    auto crs = crs_from_wkt(s);
    if (crs.ok()) crs.value().source = "config";
    return crs;
  }
  std::string_view codes = s;
  if (codes.size() > 5 && detail::normalise_name(codes.substr(0, 4)) == "epsg" && codes[4] == ':') {
    codes.remove_prefix(5);
  }
  auto parse_int = [](std::string_view t, int* out) {
    if (t.empty() || t.size() > 9) return false;
    int v = 0;
    for (char ch : t) {
      if (ch < '0' || ch > '9') return false;
      v = v * 10 + (ch - '0');
    }
    *out = v;
    return true;
  };
  int horizontal = 0;
  int vertical = 0;
  const auto plus = codes.find('+');
  const bool ok = plus == std::string_view::npos
                      ? parse_int(trim(codes), &horizontal)
                      : parse_int(trim(codes.substr(0, plus)), &horizontal) &&
                            parse_int(trim(codes.substr(plus + 1)), &vertical);
  if (!ok || horizontal == 0) {
    return Error{ErrorCode::InvalidArgument,
                 "config CRS '" + std::string(s) +
                     "' is neither EPSG:<code>[+<vertical code>], WKT, PROJJSON nor a PROJ string"};
  }
  auto crs = crs_from_epsg(horizontal, vertical);
  if (crs.ok()) crs.value().source = "config (" + std::string(s) + ")";
  return crs;
}

Result<Crs> crs_from_epsg(int code, int vertical_epsg) {
  if (code <= 0 || vertical_epsg < 0) {
    return Error{ErrorCode::Unsupported,
                 "EPSG:" + std::to_string(code) + " is not a CRS in PROJ's EPSG database"};
  }
  return detail::crs_from_proj_database(code, vertical_epsg);
}

Result<Crs> crs_from_wkt(std::string_view wkt) {
  auto crs = detail::crs_from_proj_text(wkt, "WKT");
  if (crs.ok()) crs.value().source = "WKT";
  return crs;
}

std::string crs_to_wkt1(const Crs& crs) { return detail::proj_wkt1(crs.definition); }

std::string crs_to_horizontal_wkt1(const Crs& crs) {
  return detail::proj_horizontal_wkt1(crs.definition, crs.epsg);
}

namespace detail {

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

LinearUnit linear_unit_from_size(std::string name, double metres) {
  for (const LinearUnit& known : {metre_unit(), international_foot_unit(), us_survey_foot_unit()}) {
    if (std::fabs(metres - known.metres) <= 1e-12 * known.metres) return known;
  }
  return LinearUnit{std::move(name), metres, 0};
}

AngularUnit angular_unit_from_size(std::string name, double radians) {
  if (std::fabs(radians - kDegree) <= 1e-12 * kDegree) return degree_unit();
  return AngularUnit{std::move(name), radians, 0};
}

Helmert7 helmert_from_position_vector(double tx, double ty, double tz, double rx, double ry,
                                      double rz, double ppm) {
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

std::optional<double> proj_parameter(const std::string& proj_string, std::string_view key) {
  std::istringstream in(proj_string);
  const std::string prefix = "+" + std::string(key) + "=";
  for (std::string t; in >> t;) {
    if (t.rfind(prefix, 0) != 0) continue;
    const std::string value = t.substr(prefix.size());
    char* end = nullptr;
    const double v = std::strtod(value.c_str(), &end);
    if (end == value.c_str() || *end != '\0' || !std::isfinite(v)) return std::nullopt;
    return v;
  }
  return std::nullopt;
}

bool proj_has(const std::string& proj_string, std::string_view token) {
  std::istringstream in(proj_string);
  for (std::string t; in >> t;) {
    if (t == token) return true;
  }
  return false;
}

}  // namespace detail

}  // namespace csgtile::geo
