// The CRS model's small functions: units, validation, comparison, reconciliation, text.

#include <cmath>
#include <cstdlib>
#include <string>

#include "crs/crs_internal.h"

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

const char* projection_method_name(ProjectionMethod method) {
  switch (method) {
    case ProjectionMethod::TransverseMercator:
      return "Transverse Mercator";
    case ProjectionMethod::LambertConicConformal1SP:
      return "Lambert Conic Conformal (1SP)";
    case ProjectionMethod::LambertConicConformal2SP:
      return "Lambert Conic Conformal (2SP)";
    case ProjectionMethod::PolarStereographicA:
      return "Polar Stereographic (variant A)";
    case ProjectionMethod::PolarStereographicB:
      return "Polar Stereographic (variant B)";
    case ProjectionMethod::ObliqueStereographic:
      return "Oblique Stereographic";
    case ProjectionMethod::ComputedByProj:
      return "computed by PROJ";
  }
  return "?";
}

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

bool latitude_ok(double lat) { return std::fabs(lat) <= 90.0; }

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
  const Projection& p = *crs.projection;
  if (p.method == ProjectionMethod::ComputedByProj) {
    if (p.proj_string.empty()) return invalid(p.method_name + ": no PROJ definition");
    return Status();
  }
  const std::string method = projection_method_name(p.method);
  if (!finite_all({p.latitude_of_origin_deg, p.longitude_of_origin_deg, p.scale_factor,
                   p.standard_parallel_1_deg, p.standard_parallel_2_deg, p.false_easting_m,
                   p.false_northing_m})) {
    return invalid(method + ": non-finite parameter");
  }
  if (!latitude_ok(p.latitude_of_origin_deg) || !latitude_ok(p.standard_parallel_1_deg) ||
      !latitude_ok(p.standard_parallel_2_deg)) {
    return invalid(method + ": a latitude parameter is outside ±90 degrees");
  }
  if (std::fabs(p.longitude_of_origin_deg) > 360.0) {
    return invalid(method + ": longitude of origin outside ±360 degrees");
  }
  switch (p.method) {
    case ProjectionMethod::TransverseMercator:
    case ProjectionMethod::ObliqueStereographic:
    case ProjectionMethod::LambertConicConformal1SP:
    case ProjectionMethod::PolarStereographicA:
      if (!(p.scale_factor > 0)) return invalid(method + ": scale factor must be positive");
      break;
    default:
      break;
  }
  if (p.method == ProjectionMethod::LambertConicConformal1SP &&
      (p.latitude_of_origin_deg == 0.0 || std::fabs(p.latitude_of_origin_deg) == 90.0)) {
    return invalid(method +
                   ": latitude of natural origin must be strictly between the equator and a pole");
  }
  if (p.method == ProjectionMethod::LambertConicConformal2SP) {
    if (p.standard_parallel_1_deg + p.standard_parallel_2_deg == 0.0) {
      return invalid(method + ": standard parallels symmetric about the equator");
    }
    if (std::fabs(p.standard_parallel_1_deg) == 90.0 ||
        std::fabs(p.standard_parallel_2_deg) == 90.0) {
      return invalid(method + ": a standard parallel at a pole");
    }
  }
  if (p.method == ProjectionMethod::PolarStereographicA &&
      std::fabs(p.latitude_of_origin_deg) != 90.0) {
    return invalid(method + ": latitude of natural origin must be ±90, got " +
                   detail::format_number(p.latitude_of_origin_deg));
  }
  if (p.method == ProjectionMethod::PolarStereographicB &&
      (p.standard_parallel_1_deg == 0.0 || std::fabs(p.standard_parallel_1_deg) == 90.0 ||
       (std::fabs(p.latitude_of_origin_deg) == 90.0 &&
        (p.latitude_of_origin_deg > 0) != (p.standard_parallel_1_deg > 0)))) {
    return invalid(method +
                   ": the standard parallel must lie strictly between the equator and the pole");
  }
  if (p.method == ProjectionMethod::ObliqueStereographic &&
      std::fabs(p.latitude_of_origin_deg) == 90.0) {
    return invalid(method + ": latitude of origin at a pole (use a polar stereographic method)");
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
  return p.method == ProjectionMethod::ComputedByProj && !p.method_name.empty()
             ? p.method_name
             : std::string(projection_method_name(p.method));
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
    const Projection& pa = *a.projection;
    const Projection& pb = *b.projection;
    if (pa.method != pb.method) {
      return both("projection method", method_label(pa), method_label(pb));
    }
    if (pa.method == ProjectionMethod::ComputedByProj) {
      if (pa.proj_string != pb.proj_string) {
        return both("projection (PROJ)", pa.proj_string, pb.proj_string);
      }
      return std::nullopt;
    }
    struct Field {
      const char* name;
      double va, vb, tolerance;
    };
    const Field fields[] = {
        {"latitude of origin", pa.latitude_of_origin_deg, pb.latitude_of_origin_deg, 1e-9},
        {"longitude of origin", pa.longitude_of_origin_deg, pb.longitude_of_origin_deg, 1e-9},
        {"scale factor", pa.scale_factor, pb.scale_factor, 1e-10},
        {"standard parallel 1", pa.standard_parallel_1_deg, pb.standard_parallel_1_deg, 1e-9},
        {"standard parallel 2", pa.standard_parallel_2_deg, pb.standard_parallel_2_deg, 1e-9},
        // EPSG rounds feet-based false origins to 0.001 ft (0.3 mm): compare to 0.5 mm.
        {"false easting (m)", pa.false_easting_m, pb.false_easting_m, 5e-4},
        {"false northing (m)", pa.false_northing_m, pb.false_northing_m, 5e-4},
    };
    for (const Field& f : fields) {
      if (std::fabs(f.va - f.vb) > f.tolerance) return both(f.name, num(f.va), num(f.vb));
    }
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
  if (s.front() == '{') {  // PROJJSON
    auto crs = detail::crs_from_proj_text(s, "PROJJSON");
    if (crs.ok()) crs.value().source = "config (PROJJSON)";
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
    return Error{
        ErrorCode::InvalidArgument,
        "config CRS '" + std::string(s) + "' is neither EPSG:<code>[+<vertical code>] nor WKT"};
  }
  auto crs = crs_from_epsg(horizontal, vertical);
  if (crs.ok()) crs.value().source = "config (" + std::string(s) + ")";
  return crs;
}

}  // namespace csgtile::geo
