// EPSG definitions from PROJ's database (Debian libproj-dev, proj-data) for the codes outside
// the built-in table: PROJ writes the CRS as WKT 1, which the WKT reader turns into a Crs; a
// datum that the table does not relate to WGS 84 gets the Helmert transformation PROJ ranks
// first for it (its name and accuracy recorded as the datum's to_wgs84_source). A CRS whose
// method this build does not compute (Krovak, Hotine oblique Mercator, Web Mercator, ...) is
// refused naming the code and the method. One PROJ context per thread.

#include <proj.h>

#include <cmath>
#include <map>
#include <mutex>
#include <string>

#include "crs/crs_internal.h"

namespace csgtile::geo::detail {

namespace {

struct Context {
  PJ_CONTEXT* ctx = proj_context_create();
  Context() { proj_log_level(ctx, PJ_LOG_NONE); }
  ~Context() { proj_context_destroy(ctx); }
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;
};

PJ_CONTEXT* context() {
  thread_local Context c;
  return c.ctx;
}

// Owns a PJ.
struct Object {
  PJ* p = nullptr;
  explicit Object(PJ* q) : p(q) {}
  ~Object() {
    if (p != nullptr) proj_destroy(p);
  }
  Object(const Object&) = delete;
  Object& operator=(const Object&) = delete;
  explicit operator bool() const { return p != nullptr; }
};

std::string label(int code) { return "EPSG:" + std::to_string(code); }

Object from_database(int code) {
  return Object(proj_create_from_database(context(), "EPSG", std::to_string(code).c_str(),
                                          PJ_CATEGORY_CRS, 0, nullptr));
}

// The first Helmert transformation PROJ ranks for `geodetic` → WGS 84 (EPSG:4326), as
// position-vector TOWGS84 values; false when it knows none (grid-only or none at all).
bool helmert_to_wgs84(const PJ* geodetic, double values[7], std::string& source) {
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
    if (proj_coordoperation_get_towgs84_values(ctx, op.p, values, 7, 0) == 0) continue;
    const char* name = proj_get_name(op.p);
    const char* auth = proj_get_id_auth_name(op.p, 0);
    const char* id = proj_get_id_code(op.p, 0);
    const double accuracy = proj_coordoperation_get_accuracy(ctx, op.p);
    source = (auth != nullptr && id != nullptr ? std::string(auth) + ":" + id + " " : "") +
             (name != nullptr ? name : "Helmert") +
             (accuracy >= 0 ? ", accuracy " + std::to_string(accuracy).substr(0, 5) + " m" : "") +
             " (chosen by PROJ " + std::string(proj_info().release).substr(0, 10) + ")";
    found = std::isfinite(values[0]) && std::isfinite(values[6]);
  }
  proj_list_destroy(ops);
  return found;
}

// The lookup itself (a query of PROJ's SQLite database and an operation search, tens of
// milliseconds); crs_from_proj_database keeps its results.
kernel::Result<Crs> lookup(int code) {
  PJ_CONTEXT* ctx = context();
  Object crs = from_database(code);
  if (!crs) {
    return kernel::Error{kernel::ErrorCode::Unsupported,
                         label(code) + " is not a CRS in PROJ's EPSG database"};
  }
  const std::string name = proj_get_name(crs.p) != nullptr ? proj_get_name(crs.p) : "";
  const PJ_TYPE type = proj_get_type(crs.p);
  if (type == PJ_TYPE_GEOCENTRIC_CRS) {
    return kernel::Error{kernel::ErrorCode::Unsupported, label(code) + " (" + name +
                                                             ") is geocentric: tiles are read in a "
                                                             "geographic or projected CRS"};
  }
  const char* options[] = {"MULTILINE=NO", nullptr};
  const char* wkt = proj_as_wkt(ctx, crs.p, PJ_WKT1_GDAL, options);
  if (wkt == nullptr) {
    return kernel::Error{kernel::ErrorCode::Unsupported,
                         label(code) + " (" + name + ") cannot be written as WKT 1 by PROJ"};
  }
  auto parsed = crs_from_wkt(wkt);
  if (!parsed.ok()) {
    return kernel::Error{
        parsed.error().code,
        label(code) + " (" + name + ", from PROJ's database): " + parsed.error().message};
  }
  Crs out = std::move(parsed).value();
  out.epsg = type == PJ_TYPE_COMPOUND_CRS ? out.epsg : code;
  if (type != PJ_TYPE_COMPOUND_CRS) out.name = name;
  out.source = label(code) + " (PROJ database)";
  const GeodeticDatum& d = out.datum;
  const bool settled =
      d.epsg == 6326 ||
      (d.to_wgs84 && d.to_wgs84_source.rfind("assumed", 0) != 0 && d.to_wgs84_source != "unknown");
  if (!settled) {
    Object geodetic(proj_crs_get_geodetic_crs(ctx, crs.p));
    double v[7] = {0, 0, 0, 0, 0, 0, 0};
    std::string source;
    if (geodetic && helmert_to_wgs84(geodetic.p, v, source)) {
      out.datum.to_wgs84 = helmert_from_position_vector(v[0], v[1], v[2], v[3], v[4], v[5], v[6]);
      out.datum.to_wgs84_source = source;
      // The WKT reader's "not known" warnings no longer hold.
      std::erase_if(out.warnings, [](const std::string& w) {
        return w.find("is not known") != std::string::npos;
      });
    }
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

std::optional<VerticalCrs> vertical_from_proj_database(int code) {
  PJ_CONTEXT* ctx = context();
  Object crs = from_database(code);
  if (!crs || proj_get_type(crs.p) != PJ_TYPE_VERTICAL_CRS) return std::nullopt;
  Object cs(proj_crs_get_coordinate_system(ctx, crs.p));
  if (!cs) return std::nullopt;
  const char* unit_name = nullptr;
  const char* unit_code = nullptr;
  double factor = 0;
  if (proj_cs_get_axis_info(ctx, cs.p, 0, nullptr, nullptr, nullptr, &factor, &unit_name, nullptr,
                            &unit_code) == 0 ||
      !(factor > 0)) {
    return std::nullopt;
  }
  VerticalCrs v;
  v.epsg = code;
  v.name = proj_get_name(crs.p) != nullptr ? proj_get_name(crs.p) : label(code);
  v.unit.name = unit_name != nullptr ? unit_name : "metre";
  v.unit.metres = factor;
  v.unit.epsg = unit_code != nullptr ? std::atoi(unit_code) : 0;
  return v;
}

}  // namespace csgtile::geo::detail
