// CRSs PROJ reads (Debian libproj-dev, proj-data): EPSG codes outside the built-in table,
// and WKT / PROJJSON our own reader does not model. PROJ writes the CRS as WKT 1, which the
// WKT reader turns into a Crs; a datum that the table does not relate to WGS 84 gets the
// Helmert transformation PROJ ranks first for it (its name and accuracy recorded as the
// datum's to_wgs84_source). A projection method our engines do not compute (Krovak, Hotine
// oblique Mercator, Mercator, LAEA, Albers, ...) is kept as PROJ's own projection string
// (ProjectionMethod::ComputedByProj); geocentric CRSs get their datum and unit from PROJ.
// One PROJ context per thread.

#include <cmath>
#include <cstdlib>
#include <map>
#include <mutex>
#include <sstream>
#include <string>
#include <string_view>

#include "crs/crs_internal.h"
#include "crs/proj_context.h"

namespace csgtile::geo::detail {

namespace {

PJ_CONTEXT* context() { return proj_thread_context(); }
using Object = ProjObject;

std::string label(int code) { return "EPSG:" + std::to_string(code); }

Object from_database(int code) {
  return Object(proj_create_from_database(context(), "EPSG", std::to_string(code).c_str(),
                                          PJ_CATEGORY_CRS, 0, nullptr));
}

std::string operation_label(PJ_CONTEXT* ctx, const PJ* op) {
  const char* name = proj_get_name(op);
  const char* auth = proj_get_id_auth_name(op, 0);
  const char* id = proj_get_id_code(op, 0);
  const double accuracy = proj_coordoperation_get_accuracy(ctx, op);
  return (auth != nullptr && id != nullptr ? std::string(auth) + ":" + id + " " : "") +
         (name != nullptr ? name : "transformation") +
         (accuracy >= 0 ? ", accuracy " + std::to_string(accuracy).substr(0, 5) + " m" : "") +
         " (chosen by PROJ " + std::string(proj_info().release).substr(0, 10) + ")";
}

// PROJ's best transformation `geodetic` → WGS 84 (EPSG:4326) among those whose grids are
// installed, no ballpark: a Helmert (position-vector TOWGS84 values in `values`) or, when the
// best is something else (a grid shift), its PROJ pipeline in longitude/latitude degrees
// order (`pipeline`). False when PROJ knows none.
bool best_shift_to_wgs84(const PJ* geodetic, double values[7], std::string& pipeline,
                         std::string& source) {
  PJ_CONTEXT* ctx = context();
  Object wgs84(proj_create_from_database(ctx, "EPSG", "4326", PJ_CATEGORY_CRS, 0, nullptr));
  if (!wgs84) return false;
  PJ_OPERATION_FACTORY_CONTEXT* factory = proj_create_operation_factory_context(ctx, nullptr);
  if (factory == nullptr) return false;
  proj_operation_factory_context_set_grid_availability_use(
      ctx, factory, PROJ_GRID_AVAILABILITY_DISCARD_OPERATION_IF_MISSING_GRID);
  proj_operation_factory_context_set_spatial_criterion(ctx, factory,
                                                       PROJ_SPATIAL_CRITERION_PARTIAL_INTERSECTION);
  PJ_OBJ_LIST* ops = proj_create_operations(ctx, geodetic, wgs84.p, factory);
  proj_operation_factory_context_destroy(factory);
  if (ops == nullptr) return false;
  bool found = false;
  const int n = proj_list_get_count(ops);
  for (int i = 0; i < n && !found; ++i) {
    Object op(proj_list_get(ctx, ops, i));
    if (!op || proj_coordoperation_has_ballpark_transformation(ctx, op.p) != 0) continue;
    if (proj_coordoperation_get_towgs84_values(ctx, op.p, values, 7, 0) != 0) {
      found = std::isfinite(values[0]) && std::isfinite(values[6]);
      pipeline.clear();
    } else {
      // Not a Helmert: keep PROJ's own pipeline when it can run here (its grids found).
      if (proj_coordoperation_is_instantiable(ctx, op.p) == 0) continue;
      Object normal(proj_normalize_for_visualization(ctx, op.p));
      const char* text = normal ? proj_as_proj_string(ctx, normal.p, PJ_PROJ_5, nullptr) : nullptr;
      if (text == nullptr) continue;
      pipeline = text;
      found = true;
    }
    if (found) source = operation_label(ctx, op.p);
  }
  proj_list_destroy(ops);
  return found;
}

// Settles a datum the WKT reader could not relate to WGS 84 with the Helmert PROJ ranks first.
void settle_datum(const PJ* crs, Crs& out) {
  const GeodeticDatum& d = out.datum;
  const bool settled =
      d.epsg == 6326 ||
      (d.to_wgs84 && d.to_wgs84_source.rfind("assumed", 0) != 0 && d.to_wgs84_source != "unknown");
  if (settled) return;
  Object geodetic(proj_crs_get_geodetic_crs(context(), crs));
  double v[7] = {0, 0, 0, 0, 0, 0, 0};
  std::string source;
  std::string pipeline;
  if (geodetic && best_shift_to_wgs84(geodetic.p, v, pipeline, source)) {
    if (pipeline.empty()) {
      out.datum.to_wgs84 = helmert_from_position_vector(v[0], v[1], v[2], v[3], v[4], v[5], v[6]);
    } else {
      out.datum.to_wgs84.reset();
      out.datum.to_wgs84_pipeline = pipeline;
    }
    out.datum.to_wgs84_source = source;
    // The WKT reader's "not known" warnings no longer hold.
    std::erase_if(out.warnings,
                  [](const std::string& w) { return w.find("is not known") != std::string::npos; });
  }
}

std::string text_of(const char* s) { return s != nullptr ? s : ""; }

// PROJ's WKT 1 (GDAL dialect) of a CRS, one line; empty when PROJ cannot write it.
std::string wkt1_of(const PJ* crs) {
  const char* options[] = {"MULTILINE=NO", nullptr};
  return text_of(proj_as_wkt(context(), crs, PJ_WKT1_GDAL, options));
}

// "EPSG" code of a PROJ object's first identifier; 0 when it has none from EPSG.
int epsg_of(const PJ* object) {
  const char* auth = proj_get_id_auth_name(object, 0);
  const char* code = proj_get_id_code(object, 0);
  return auth != nullptr && code != nullptr && std::string_view(auth) == "EPSG" ? std::atoi(code)
                                                                                : 0;
}

// The unit of a CRS's first axis (snapped to metre / foot / US survey foot, its EPSG code
// kept); nullopt when PROJ gives none.
std::optional<LinearUnit> axis_unit(const PJ* crs) {
  PJ_CONTEXT* ctx = context();
  Object cs(proj_crs_get_coordinate_system(ctx, crs));
  double factor = 0.0;
  const char* unit_name = nullptr;
  const char* unit_code = nullptr;
  if (!cs ||
      proj_cs_get_axis_info(ctx, cs.p, 0, nullptr, nullptr, nullptr, &factor, &unit_name, nullptr,
                            &unit_code) == 0 ||
      !(factor > 0) || !std::isfinite(factor)) {
    return std::nullopt;
  }
  LinearUnit unit = linear_unit_from_size(text_of(unit_name), factor);
  if (unit_code != nullptr && unit.epsg == 0) unit.epsg = std::atoi(unit_code);
  return unit;
}

// A vertical CRS's name, code and unit; nullopt when `crs` is none.
std::optional<VerticalCrs> vertical_of(const PJ* crs) {
  if (crs == nullptr || proj_get_type(crs) != PJ_TYPE_VERTICAL_CRS) return std::nullopt;
  const auto unit = axis_unit(crs);
  if (!unit) return std::nullopt;
  VerticalCrs v;
  v.epsg = epsg_of(crs);
  v.name = text_of(proj_get_name(crs));
  v.unit = *unit;
  return v;
}

// The projection part of a projected CRS's PROJ string: the projection and its ellipsoid,
// in metres; what CrsMath does itself (units, prime meridian) and what is no projection
// (datum shifts, grids, the CRS marker) removed.
std::string projection_string(const PJ* crs, const Ellipsoid& ellipsoid, std::string* why) {
  const char* raw = proj_as_proj_string(context(), crs, PJ_PROJ_4, nullptr);
  if (raw == nullptr) {
    *why = "PROJ cannot write it as a PROJ string";
    return std::string();
  }
  std::istringstream in(raw);
  std::string out;
  for (std::string t; in >> t;) {
    const std::string key = t.substr(0, t.find('='));
    if (key == "+type" || key == "+no_defs" || key == "+towgs84" || key == "+nadgrids" ||
        key == "+geoidgrids" || key == "+units" || key == "+to_meter" || key == "+vunits" ||
        key == "+vto_meter" || key == "+pm" || key == "+wktext" || key == "+datum") {
      continue;
    }
    out += (out.empty() ? "" : " ") + t;
  }
  if (out.rfind("+proj=", 0) != 0) {
    *why = "its PROJ string '" + std::string(raw) + "' is not a projection";
    return std::string();
  }
  // A +datum named the ellipsoid: without it, the base CRS's.
  return with_earth(out, ellipsoid);
}

// A projected CRS whose method our engines do not compute: its base geographic CRS read by
// our WKT reader, its unit from the coordinate system, the projection left to PROJ.
kernel::Result<Crs> projected_by_proj(const PJ* crs, const std::string& what) {
  PJ_CONTEXT* ctx = context();
  const std::string name = text_of(proj_get_name(crs));
  Object geodetic(proj_crs_get_geodetic_crs(ctx, crs));
  if (!geodetic) {
    return kernel::Error{kernel::ErrorCode::Unsupported,
                         what + " (" + name + ") has no base geodetic CRS"};
  }
  auto base = crs_from_wkt_own(wkt1_of(geodetic.p));
  if (!base.ok()) {
    return kernel::Error{base.error().code,
                         what + " (" + name + "), its base CRS: " + base.error().message};
  }
  Crs out = std::move(base).value();
  settle_datum(crs, out);
  const auto unit = axis_unit(crs);
  if (!unit) {
    return kernel::Error{kernel::ErrorCode::Unsupported,
                         what + " (" + name + "): PROJ gives no unit for its axes"};
  }
  out.linear_unit = *unit;
  Object conversion(proj_crs_get_coordoperation(ctx, crs));
  const char* method = nullptr;
  if (conversion) proj_coordoperation_get_method_info(ctx, conversion.p, &method, nullptr, nullptr);
  Projection p;
  p.method = ProjectionMethod::ComputedByProj;
  p.method_name = method != nullptr ? method : "PROJ projection";
  std::string why;
  p.proj_string = projection_string(crs, out.datum.ellipsoid, &why);
  if (p.proj_string.empty()) {
    return kernel::Error{kernel::ErrorCode::Unsupported, what + " (" + name + "): " + why};
  }
  p.wkt1 = wkt1_of(crs);
  out.kind = CrsKind::Projected;
  out.name = name;
  out.epsg = epsg_of(crs);
  out.projection = std::move(p);
  out.angular_unit = degree_unit();
  return out;
}

// A geocentric CRS: datum and ellipsoid from PROJ (the table's relation to WGS 84 where it
// knows the datum), x, y, z in the axes' unit.
kernel::Result<Crs> geocentric_of(const PJ* crs, const std::string& what) {
  PJ_CONTEXT* ctx = context();
  Crs out;
  out.kind = CrsKind::Geocentric;
  out.name = text_of(proj_get_name(crs));
  out.epsg = epsg_of(crs);
  Object datum(proj_crs_get_datum_forced(ctx, crs));
  Object ellipsoid(proj_get_ellipsoid(ctx, crs));
  double a = 0, b = 0, rf = 0;
  int computed = 0;
  if (!datum || !ellipsoid ||
      proj_ellipsoid_get_parameters(ctx, ellipsoid.p, &a, &b, &computed, &rf) == 0) {
    return kernel::Error{kernel::ErrorCode::Unsupported,
                         what + " (" + out.name + "): PROJ gives no datum"};
  }
  const char* datum_code = proj_get_id_code(datum.p, 0);
  if (auto known = datum_code != nullptr ? datum_from_epsg(std::atoi(datum_code)) : std::nullopt) {
    out.datum = *known;
  } else {
    out.datum.name = text_of(proj_get_name(datum.p));
    out.datum.epsg = datum_code != nullptr ? std::atoi(datum_code) : 0;
    out.datum.ellipsoid.name = text_of(proj_get_name(ellipsoid.p));
    const char* e_code = proj_get_id_code(ellipsoid.p, 0);
    out.datum.ellipsoid.epsg = e_code != nullptr ? std::atoi(e_code) : 0;
    out.datum.ellipsoid.semi_major_m = a;
    out.datum.ellipsoid.inverse_flattening = a == b ? 0.0 : rf;
    out.datum.to_wgs84.reset();
    out.datum.to_wgs84_source = "unknown";
    double v[7] = {0, 0, 0, 0, 0, 0, 0};
    std::string source;
    std::string pipeline;
    if (best_shift_to_wgs84(crs, v, pipeline, source) && pipeline.empty()) {
      out.datum.to_wgs84 = helmert_from_position_vector(v[0], v[1], v[2], v[3], v[4], v[5], v[6]);
      out.datum.to_wgs84_source = source;
    }
  }
  Object pm(proj_get_prime_meridian(ctx, crs));
  double longitude = 0, angle_unit = 0;
  if (pm && proj_prime_meridian_get_parameters(ctx, pm.p, &longitude, &angle_unit, nullptr) != 0) {
    out.datum.prime_meridian_deg = longitude * angle_unit / kDegree;
  }
  const auto unit = axis_unit(crs);
  if (!unit) {
    return kernel::Error{kernel::ErrorCode::Unsupported,
                         what + " (" + out.name + "): PROJ gives no unit"};
  }
  out.linear_unit = *unit;
  out.source = what;
  return out;
}

// Any CRS PROJ made: WKT 1 through our reader where it models it, else PROJ's projection
// or a geocentric model. A compound CRS is its horizontal part plus its vertical CRS.
kernel::Result<Crs> crs_from_pj(const PJ* crs, const std::string& what) {
  PJ_CONTEXT* ctx = context();
  const std::string name = text_of(proj_get_name(crs));
  PJ_TYPE type = proj_get_type(crs);
  if (type == PJ_TYPE_BOUND_CRS) {
    Object source(proj_get_source_crs(ctx, crs));
    if (!source) return kernel::Error{kernel::ErrorCode::Unsupported, what + ": empty BOUNDCRS"};
    return crs_from_pj(source.p, what);
  }
  if (type == PJ_TYPE_GEOCENTRIC_CRS) return geocentric_of(crs, what);
  const bool known = type == PJ_TYPE_PROJECTED_CRS || type == PJ_TYPE_GEOGRAPHIC_2D_CRS ||
                     type == PJ_TYPE_GEOGRAPHIC_3D_CRS || type == PJ_TYPE_GEODETIC_CRS ||
                     type == PJ_TYPE_COMPOUND_CRS;
  if (!known) {
    return kernel::Error{
        kernel::ErrorCode::Unsupported,
        what + " (" + name + ") is no geographic, projected, geocentric or compound CRS"};
  }
  auto parsed = crs_from_wkt_own(wkt1_of(crs));
  if (parsed.ok()) {
    Crs out = std::move(parsed).value();
    settle_datum(crs, out);
    return out;
  }
  if (parsed.error().code != kernel::ErrorCode::Unsupported) {
    return kernel::Error{parsed.error().code, what + " (" + name + "): " + parsed.error().message};
  }
  if (type == PJ_TYPE_PROJECTED_CRS) return projected_by_proj(crs, what);
  if (type == PJ_TYPE_COMPOUND_CRS) {
    Object horizontal(proj_crs_get_sub_crs(ctx, crs, 0));
    Object vertical(proj_crs_get_sub_crs(ctx, crs, 1));
    if (!horizontal)
      return kernel::Error{kernel::ErrorCode::Unsupported, what + ": empty compound CRS"};
    auto h = crs_from_pj(horizontal.p, what);
    if (!h.ok()) return h;
    Crs out = std::move(h).value();
    if (out.kind == CrsKind::Geocentric) {
      return kernel::Error{kernel::ErrorCode::Unsupported,
                           what + ": a geocentric CRS in a compound CRS"};
    }
    if (vertical && proj_get_type(vertical.p) == PJ_TYPE_VERTICAL_CRS) {
      VerticalCrs v{epsg_of(vertical.p), text_of(proj_get_name(vertical.p)), metre_unit()};
      if (auto read = vertical_of(vertical.p)) v = *read;
      out.vertical = v;
    }
    out.name = name;
    return out;
  }
  return kernel::Error{parsed.error().code, what + " (" + name + "): " + parsed.error().message};
}

// The lookup itself (a query of PROJ's SQLite database and an operation search, tens of
// milliseconds); crs_from_proj_database keeps its results.
kernel::Result<Crs> lookup(int code) {
  Object crs = from_database(code);
  if (!crs) {
    return kernel::Error{kernel::ErrorCode::Unsupported,
                         label(code) + " is not a CRS in PROJ's EPSG database"};
  }
  const std::string name = text_of(proj_get_name(crs.p));
  const PJ_TYPE type = proj_get_type(crs.p);
  auto made = crs_from_pj(crs.p, label(code));
  if (!made.ok()) return made;
  Crs out = std::move(made).value();
  out.epsg = type == PJ_TYPE_COMPOUND_CRS ? out.epsg : code;
  if (type != PJ_TYPE_COMPOUND_CRS) out.name = name;
  out.source = label(code) + " (PROJ database)";
  if (auto status = validate_crs(out); !status.ok()) {
    return kernel::Error{status.error().code, label(code) + ": " + status.error().message};
  }
  return out;
}

}  // namespace

kernel::Result<Crs> crs_from_proj_database(int code) {
  // Every job of a run asks again for the same few codes: each is looked up once per process.
  // The database does not change while the process runs; the bound keeps hostile inputs
  // (random codes in GeoTIFF keys) from growing the memo without end.
  static std::mutex mutex;
  static std::map<int, kernel::Result<Crs>> memo;
  {
    const std::lock_guard<std::mutex> lock(mutex);
    if (auto it = memo.find(code); it != memo.end()) return it->second;
  }
  kernel::Result<Crs> found = lookup(code);
  const std::lock_guard<std::mutex> lock(mutex);
  if (memo.size() < 4096) memo.emplace(code, found);
  return found;
}

kernel::Result<Crs> crs_from_proj_text(std::string_view text, const std::string& what) {
  constexpr std::size_t kMaxLength = 1 << 16;
  if (text.size() > kMaxLength) {
    return kernel::Error{kernel::ErrorCode::InvalidArgument,
                         what + " longer than " + std::to_string(kMaxLength) + " bytes"};
  }
  const std::string owned(text);
  if (owned.find('\0') != std::string::npos) {
    return kernel::Error{kernel::ErrorCode::InvalidArgument, what + " contains a NUL byte"};
  }
  Object crs(proj_create(context(), owned.c_str()));
  if (!crs) {
    const std::string why = proj_last_error();
    return kernel::Error{kernel::ErrorCode::Unsupported,
                         what + " is not a CRS PROJ can read" + (why.empty() ? "" : ": " + why)};
  }
  if (proj_is_crs(crs.p) == 0) {
    return kernel::Error{kernel::ErrorCode::Unsupported, what + " describes no CRS"};
  }
  auto out = crs_from_pj(crs.p, what);
  if (!out.ok()) return out;
  out.value().source = what + " (read by PROJ)";
  if (auto status = validate_crs(out.value()); !status.ok()) {
    return kernel::Error{status.error().code, what + ": " + status.error().message};
  }
  return out;
}

std::string proj_projected_wkt1(const Crs& crs) {
  if (!crs.projection) return std::string();
  const Projection& p = *crs.projection;
  std::string text = with_earth(p.proj_string, crs.datum.ellipsoid);
  if (crs.datum.prime_meridian_deg != 0.0)
    text += " +pm=" + format_number(crs.datum.prime_meridian_deg);
  if (crs.datum.to_wgs84 && !crs.datum.to_wgs84->is_null()) {
    const Helmert7& h = *crs.datum.to_wgs84;  // +towgs84 is position vector: negate rotations
    text += " +towgs84=" + format_number(h.tx_m) + "," + format_number(h.ty_m) + "," +
            format_number(h.tz_m) + "," + format_number(-h.rx_arcsec + 0.0) + "," +
            format_number(-h.ry_arcsec + 0.0) + "," + format_number(-h.rz_arcsec + 0.0) + "," +
            format_number(h.scale_ppm);
  }
  text += " +to_meter=" + format_number(crs.linear_unit.metres) + " +no_defs +type=crs";
  Object made(proj_create(context(), text.c_str()));
  return made ? wkt1_of(made.p) : std::string();
}

std::optional<VerticalCrs> vertical_from_proj_database(int code) {
  Object crs = from_database(code);
  auto v = vertical_of(crs.p);
  if (v) v->epsg = code;
  return v;
}

std::string with_earth(const std::string& proj_string, const Ellipsoid& ellipsoid) {
  for (const char* key : {"+ellps=", "+a=", "+R=", "+datum="}) {
    if (proj_string.find(key) != std::string::npos) return proj_string;
  }
  const std::string earth = ellipsoid.inverse_flattening == 0.0
                                ? "+R=" + format_number(ellipsoid.semi_major_m)
                                : "+a=" + format_number(ellipsoid.semi_major_m) +
                                      " +rf=" + format_number(ellipsoid.inverse_flattening);
  return proj_string.empty() ? earth : proj_string + " " + earth;
}

}  // namespace csgtile::geo::detail
