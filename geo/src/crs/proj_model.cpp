// Every CRS as PROJ reads it (Debian libproj-dev, proj-data), turned into the Crs model:
// the datum, its ellipsoid and prime meridian, the units of the axes, the projection as a
// PROJ string, the vertical CRS, and the transformations PROJ ranks first among those whose
// grids are installed — the datum's to WGS 84 (a Helmert, or PROJ's own pipeline for a grid
// shift) and the vertical CRS's to ellipsoidal heights (a geoid model). One PROJ context per
// thread; lookups are remembered per process (they query PROJ's SQLite database).

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <map>
#include <mutex>
#include <sstream>
#include <string>
#include <string_view>
#include <utility>

#include "crs/crs_internal.h"
#include "crs/proj_context.h"

#include <proj_experimental.h>

namespace csgtile::geo::detail {

namespace {

using kernel::Error;
using kernel::ErrorCode;
using kernel::Result;

PJ_CONTEXT* context() { return proj_thread_context(); }
using Object = ProjObject;

std::string text_of(const char* s) { return s != nullptr ? s : ""; }

// "EPSG" code of a PROJ object's first identifier; 0 when it has none from EPSG.
int epsg_of(const PJ* object) {
  const char* auth = proj_get_id_auth_name(object, 0);
  const char* code = proj_get_id_code(object, 0);
  return auth != nullptr && code != nullptr && std::string_view(auth) == "EPSG" ? std::atoi(code)
                                                                                : 0;
}

// The EPSG code of a CRS without one of its own: PROJ's identification, when exactly one
// candidate is at the best confidence and that is at least 70 (the same CRS, its names
// aside). 0 otherwise.
int identified_epsg(const PJ* crs) {
  if (const int own = epsg_of(crs)) return own;
  int* confidence = nullptr;
  PJ_OBJ_LIST* list = proj_identify(proj_thread_context(), crs, "EPSG", nullptr, &confidence);
  int code = 0;
  if (list != nullptr) {
    const int n = proj_list_get_count(list);
    int best = 0;
    int count = 0;
    for (int i = 0; i < n; ++i) {
      if (confidence[i] > best) {
        best = confidence[i];
        count = 0;
      }
      if (confidence[i] == best) ++count;
    }
    if (best >= 70 && count == 1) {
      for (int i = 0; i < n && code == 0; ++i) {
        if (confidence[i] != best) continue;
        ProjObject match(proj_list_get(proj_thread_context(), list, i));
        code = match ? epsg_of(match.p) : 0;
      }
    }
    proj_list_destroy(list);
  }
  proj_int_list_destroy(confidence);
  return code;
}

Object from_database(int code, PJ_CATEGORY category) {
  return Object(proj_create_from_database(context(), "EPSG", std::to_string(code).c_str(), category,
                                          0, nullptr));
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

// The operations PROJ finds from `source` to `target` whose grids are installed, best first.
PJ_OBJ_LIST* operations(const PJ* source, const PJ* target) {
  PJ_CONTEXT* ctx = context();
  PJ_OPERATION_FACTORY_CONTEXT* factory = proj_create_operation_factory_context(ctx, nullptr);
  if (factory == nullptr) return nullptr;
  proj_operation_factory_context_set_grid_availability_use(
      ctx, factory, PROJ_GRID_AVAILABILITY_DISCARD_OPERATION_IF_MISSING_GRID);
  proj_operation_factory_context_set_spatial_criterion(ctx, factory,
                                                       PROJ_SPATIAL_CRITERION_PARTIAL_INTERSECTION);
  PJ_OBJ_LIST* ops = proj_create_operations(ctx, source, target, factory);
  proj_operation_factory_context_destroy(factory);
  return ops;
}

// PROJ's pipeline of an operation in longitude/latitude degrees order; empty when PROJ cannot
// write one.
std::string pipeline_of(const PJ* op) {
  Object normal(proj_normalize_for_visualization(context(), op));
  const char* text =
      normal ? proj_as_proj_string(context(), normal.p, PJ_PROJ_5, nullptr) : nullptr;
  return text_of(text);
}

// The first of PROJ's operations `source` → `target` (best first, grids installed) that is no
// ballpark and that `take` accepts; `take` records what it needs and its label (the operation's
// name, code and accuracy) is set. False when none is taken.
template <typename Take>
bool take_best_operation(const PJ* source, const PJ* target, std::string& label, Take take) {
  PJ_CONTEXT* ctx = context();
  PJ_OBJ_LIST* ops = operations(source, target);
  if (ops == nullptr) return false;
  bool taken = false;
  const int n = proj_list_get_count(ops);
  for (int i = 0; i < n && !taken; ++i) {
    Object op(proj_list_get(ctx, ops, i));
    if (!op || proj_coordoperation_has_ballpark_transformation(ctx, op.p) != 0) continue;
    taken = take(op.p);
    if (taken) label = operation_label(ctx, op.p);
  }
  proj_list_destroy(ops);
  return taken;
}

// A pipeline PROJ can run here (its grids found), or empty.
std::string runnable_pipeline(const PJ* op) {
  return proj_coordoperation_is_instantiable(context(), op) != 0 ? pipeline_of(op) : std::string();
}

// PROJ's best transformation `geodetic` → WGS 84 (EPSG:4326) among those whose grids are
// installed, no ballpark: a Helmert (position-vector TOWGS84 values in `values`) or, when the
// best is something else (a grid shift), its PROJ pipeline. False when PROJ knows none.
bool best_shift_to_wgs84(const PJ* geodetic, double values[7], std::string& pipeline,
                         std::string& source) {
  Object wgs84 = from_database(4326, PJ_CATEGORY_CRS);
  if (!wgs84) return false;
  return take_best_operation(geodetic, wgs84.p, source, [&](const PJ* op) {
    if (proj_coordoperation_get_towgs84_values(context(), op, values, 7, 0) != 0) {
      pipeline.clear();
      return std::isfinite(values[0]) && std::isfinite(values[6]);
    }
    pipeline = runnable_pipeline(op);
    return !pipeline.empty();
  });
}

// A bound CRS's source CRS (kept alive by `holder`); any other CRS itself.
const PJ* unbound(const PJ* crs, Object& holder) {
  if (crs == nullptr || proj_get_type(crs) != PJ_TYPE_BOUND_CRS) return crs;
  holder = Object(proj_get_source_crs(context(), crs));
  return holder ? holder.p : crs;
}

// The unit of a CRS's first axis: (name, size in SI units — metres or radians, EPSG code).
struct AxisUnit {
  std::string name;
  double factor = 0.0;
  int epsg = 0;
};

std::optional<AxisUnit> axis_unit(const PJ* crs) {
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
  return AxisUnit{text_of(unit_name), factor, unit_code != nullptr ? std::atoi(unit_code) : 0};
}

LinearUnit linear_of(const AxisUnit& u) {
  LinearUnit unit = linear_unit_from_size(u.name, u.factor);
  if (u.epsg != 0) unit.epsg = u.epsg;
  return unit;
}

bool is_wgs84_datum(const PJ* datum) {
  const int code = epsg_of(datum);
  if (code == 6326) return true;
  const std::string name = normalise_name(text_of(proj_get_name(datum)));
  return name == "wgs84" || name == "worldgeodeticsystem1984" ||
         name.rfind("worldgeodeticsystem1984ensemble", 0) == 0;
}

// The datum of a geodetic (geographic or geocentric) CRS, with its relation to WGS 84: the
// definition's own TOWGS84 (`given`, a bound CRS's) or PROJ's best.
Result<GeodeticDatum> datum_of(const PJ* geodetic, const std::string& what,
                               const std::optional<Helmert7>& given,
                               std::vector<std::string>& warnings) {
  PJ_CONTEXT* ctx = context();
  Object datum(proj_crs_get_datum_forced(ctx, geodetic));
  Object ellipsoid(proj_get_ellipsoid(ctx, geodetic));
  double a = 0, b = 0, rf = 0;
  int computed = 0;
  if (!datum || !ellipsoid ||
      proj_ellipsoid_get_parameters(ctx, ellipsoid.p, &a, &b, &computed, &rf) == 0) {
    return Error{ErrorCode::Unsupported, what + ": PROJ gives no datum or ellipsoid"};
  }
  GeodeticDatum out;
  out.name = text_of(proj_get_name(datum.p));
  out.epsg = epsg_of(datum.p);
  out.ellipsoid.name = text_of(proj_get_name(ellipsoid.p));
  out.ellipsoid.epsg = epsg_of(ellipsoid.p);
  out.ellipsoid.semi_major_m = a;
  out.ellipsoid.inverse_flattening = a == b ? 0.0 : rf;
  Object pm(proj_get_prime_meridian(ctx, geodetic));
  double longitude = 0, angle_unit = 0;
  if (pm && proj_prime_meridian_get_parameters(ctx, pm.p, &longitude, &angle_unit, nullptr) != 0) {
    out.prime_meridian_deg = longitude * angle_unit / kDegree;
  }
  auto given_or = [&](Helmert7 h, const char* source) {
    out.to_wgs84 = given ? *given : h;
    out.to_wgs84_source = given ? "TOWGS84 of the definition" : source;
    return out;
  };
  if (is_wgs84_datum(datum.p)) return given_or(Helmert7{}, "identity");
  // The transformation is looked up from the database's own CRS of the datum where there is
  // one, so a CRS read from WKT (any axis order, no identifiers) gets the same one as its
  // EPSG code.
  Object database;
  if (const int code = identified_epsg(geodetic)) database = from_database(code, PJ_CATEGORY_CRS);
  if (!database && out.epsg != 0) {
    if (const int code = geographic_crs_of_datum(out.epsg)) {
      database = from_database(code, PJ_CATEGORY_CRS);
    }
  }
  if (database) {
    Object database_datum(proj_crs_get_datum_forced(ctx, database.p));
    if (database_datum && out.epsg == 0) out.epsg = epsg_of(database_datum.p);
  }
  if (given) return given_or(*given, "");
  double v[7] = {0, 0, 0, 0, 0, 0, 0};
  std::string pipeline;
  std::string source;
  if (best_shift_to_wgs84(database ? database.p : geodetic, v, pipeline, source)) {
    if (pipeline.empty()) {
      out.to_wgs84 = helmert_from_position_vector(v[0], v[1], v[2], v[3], v[4], v[5], v[6]);
    } else {
      out.to_wgs84.reset();
      out.to_wgs84_pipeline = pipeline;
    }
    out.to_wgs84_source = source;
    return out;
  }
  const bool wgs84_like = a == 6378137.0 && std::fabs(rf - 298.2572) < 1e-3;
  if (wgs84_like) {
    // As PROJ's ballpark does: a datum on the WGS 84 / GRS 80 ellipsoid is taken as WGS 84.
    out.to_wgs84 = Helmert7{};
    out.to_wgs84_source = "assumed null (datum on a WGS 84/GRS 80 ellipsoid)";
    warnings.push_back("datum '" + out.name + "' on the " + out.ellipsoid.name +
                       " ellipsoid assumed equal to WGS 84 (PROJ knows no transformation)");
  } else {
    out.to_wgs84.reset();
    out.to_wgs84_source = "unknown";
    warnings.push_back("datum '" + out.name +
                       "' has no transformation to WGS 84 that PROJ knows with installed grids "
                       "and no TOWGS84: it cannot be placed on the globe");
  }
  return out;
}

// The projection part of a projected CRS's PROJ string: the projection and its ellipsoid,
// in metres; what CrsMath does itself (units, prime meridian) and what is no projection
// (datum shifts, grids, the CRS marker) removed. PROJ's own earth parameters stay (Web
// Mercator's sphere is not its datum's ellipsoid); a +datum gives way to the ellipsoid.
std::string projection_string(const PJ* crs, const Ellipsoid& ellipsoid, std::string* why) {
  const char* raw = proj_as_proj_string(context(), crs, PJ_PROJ_4, nullptr);
  if (raw == nullptr) {
    *why = "PROJ cannot write its projection as a PROJ string";
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
  return with_earth(out, ellipsoid);
}

// The geoid model PROJ ranks first (grids installed, no ballpark) from `vertical` heights over
// `horizontal`'s geodetic CRS to its ellipsoidal heights. Sets the pipeline and its source,
// or says why there is none.
void settle_geoid(const PJ* horizontal, const PJ* vertical, VerticalCrs& v,
                  std::vector<std::string>& warnings) {
  PJ_CONTEXT* ctx = context();
  Object geodetic(proj_crs_get_geodetic_crs(ctx, horizontal));
  if (!geodetic) return;
  // The pipeline takes Greenwich longitudes and latitudes in degrees, as CrsMath gives them.
  const auto unit = axis_unit(geodetic.p);
  Object pm(proj_get_prime_meridian(ctx, geodetic.p));
  double pm_longitude = 0;
  if (pm) proj_prime_meridian_get_parameters(ctx, pm.p, &pm_longitude, nullptr, nullptr);
  if (!unit || std::fabs(unit->factor - kDegree) > 1e-12 * kDegree || pm_longitude != 0.0) {
    v.to_ellipsoidal_source = "not applied: the horizontal CRS is not in Greenwich degrees";
    warnings.push_back("the geoid model of " + v.name +
                       " is not applied (horizontal CRS not in Greenwich degrees): heights are "
                       "taken as ellipsoidal");
    return;
  }
  Object geodetic_3d(proj_crs_promote_to_3D(ctx, nullptr, geodetic.p));
  Object compound(proj_create_compound_crs(ctx, "heights", geodetic.p, const_cast<PJ*>(vertical)));
  if (geodetic_3d && compound) {
    take_best_operation(compound.p, geodetic_3d.p, v.to_ellipsoidal_source, [&](const PJ* op) {
      v.to_ellipsoidal_pipeline = runnable_pipeline(op);
      return !v.to_ellipsoidal_pipeline.empty();
    });
  }
  if (v.to_ellipsoidal_pipeline.empty()) {
    v.to_ellipsoidal_source = "none installed: heights taken as ellipsoidal";
    warnings.push_back("no geoid model relating " + v.name +
                       " to ellipsoidal heights is installed for PROJ: heights are taken as "
                       "ellipsoidal");
  }
}

// A vertical CRS's name, code and unit (its relation to ellipsoidal heights over `horizontal`
// when given); nullopt when `crs` is none.
std::optional<VerticalCrs> vertical_of(const PJ* crs, const PJ* horizontal,
                                       std::vector<std::string>& warnings) {
  if (crs == nullptr || proj_get_type(crs) != PJ_TYPE_VERTICAL_CRS) return std::nullopt;
  VerticalCrs v;
  v.epsg = epsg_of(crs);
  v.name = text_of(proj_get_name(crs));
  const auto unit = axis_unit(crs);
  v.unit = unit ? linear_of(*unit) : metre_unit();
  if (!unit) warnings.push_back("vertical CRS '" + v.name + "' has no unit: metre assumed");
  if (horizontal != nullptr) settle_geoid(horizontal, crs, v, warnings);
  return v;
}

std::string definition_of(const PJ* crs) {
  const char* options[] = {"MULTILINE=NO", nullptr};
  const char* wkt = proj_as_wkt(context(), crs, PJ_WKT2_2019, options);
  if (wkt != nullptr) return wkt;
  return text_of(proj_as_proj_string(context(), crs, PJ_PROJ_4, nullptr));
}

// Any CRS PROJ made. A compound CRS is its horizontal part plus its vertical CRS; a bound CRS
// its source with the definition's TOWGS84 (`given` for its datum).
Result<Crs> crs_from_pj(const PJ* crs, const std::string& what,
                        const std::optional<Helmert7>& given = std::nullopt) {
  PJ_CONTEXT* ctx = context();
  const std::string name = text_of(proj_get_name(crs));
  const PJ_TYPE type = proj_get_type(crs);
  if (type == PJ_TYPE_BOUND_CRS) {
    Object source(proj_get_source_crs(ctx, crs));
    Object transformation(proj_crs_get_coordoperation(ctx, crs));
    if (!source) return Error{ErrorCode::Unsupported, what + ": empty BOUNDCRS"};
    double v[7] = {0, 0, 0, 0, 0, 0, 0};
    std::optional<Helmert7> towgs84;
    if (transformation &&
        proj_coordoperation_get_towgs84_values(ctx, transformation.p, v, 7, 0) != 0 &&
        std::isfinite(v[0]) && std::isfinite(v[6])) {
      towgs84 = helmert_from_position_vector(v[0], v[1], v[2], v[3], v[4], v[5], v[6]);
    }
    auto out = crs_from_pj(source.p, what, towgs84);
    if (out.ok()) out.value().definition = definition_of(crs);
    return out;
  }
  if (type == PJ_TYPE_COMPOUND_CRS) {
    Object horizontal(proj_crs_get_sub_crs(ctx, crs, 0));
    Object vertical(proj_crs_get_sub_crs(ctx, crs, 1));
    if (!horizontal) return Error{ErrorCode::Unsupported, what + ": empty compound CRS"};
    auto h = crs_from_pj(horizontal.p, what);
    if (!h.ok()) return h;
    Crs out = std::move(h).value();  // its epsg: the horizontal CRS's
    if (out.kind == CrsKind::Geocentric) {
      return Error{ErrorCode::Unsupported, what + ": a geocentric CRS in a compound CRS"};
    }
    Object vertical_source, horizontal_source;
    const PJ* vertical_crs = unbound(vertical.p, vertical_source);
    out.vertical =
        vertical_of(vertical_crs, unbound(horizontal.p, horizontal_source), out.warnings);
    if (out.vertical && out.vertical->epsg == 0) out.vertical->epsg = identified_epsg(vertical_crs);
    out.name = name;
    out.definition = definition_of(crs);
    return out;
  }
  const bool geographic = type == PJ_TYPE_GEOGRAPHIC_2D_CRS || type == PJ_TYPE_GEOGRAPHIC_3D_CRS ||
                          type == PJ_TYPE_GEODETIC_CRS;
  if (!geographic && type != PJ_TYPE_PROJECTED_CRS && type != PJ_TYPE_GEOCENTRIC_CRS) {
    return Error{ErrorCode::Unsupported,
                 what + " (" + name + ") is no geographic, projected, geocentric or compound CRS"};
  }
  Crs out;
  out.name = name;
  out.epsg = identified_epsg(crs);
  out.definition = definition_of(crs);
  Object geodetic(proj_crs_get_geodetic_crs(ctx, crs));
  if (!geodetic) return Error{ErrorCode::Unsupported, what + " (" + name + ") has no datum"};
  auto datum = datum_of(geodetic.p, what + " (" + name + ")", given, out.warnings);
  if (!datum.ok()) return datum.error();
  out.datum = std::move(datum).value();
  const auto unit = axis_unit(crs);
  if (!unit) {
    return Error{ErrorCode::Unsupported, what + " (" + name + "): PROJ gives no unit for its axes"};
  }
  if (type == PJ_TYPE_GEOCENTRIC_CRS || (type == PJ_TYPE_GEODETIC_CRS && unit->factor > 1e-3)) {
    out.kind = CrsKind::Geocentric;
    out.linear_unit = linear_of(*unit);
  } else if (geographic) {
    out.kind = CrsKind::Geographic;
    out.angular_unit = angular_unit_from_size(unit->name, unit->factor);
    if (unit->epsg != 0) out.angular_unit.epsg = unit->epsg;
  } else {
    out.kind = CrsKind::Projected;
    out.linear_unit = linear_of(*unit);
    Object conversion(proj_crs_get_coordoperation(ctx, crs));
    const char* method = nullptr;
    if (conversion)
      proj_coordoperation_get_method_info(ctx, conversion.p, &method, nullptr, nullptr);
    Projection p;
    p.method_name = method != nullptr ? method : "PROJ projection";
    std::string why;
    p.proj_string = projection_string(crs, out.datum.ellipsoid, &why);
    if (p.proj_string.empty()) {
      return Error{ErrorCode::Unsupported,
                   what + " (" + name + "), method '" + p.method_name + "': " + why};
    }
    out.projection = std::move(p);
  }
  return out;
}

Result<Crs> finish(Result<Crs> made, const std::string& source, const std::string& what) {
  if (!made.ok()) return made;
  made.value().source = source;
  if (auto status = validate_crs(made.value()); !status.ok()) {
    return Error{status.error().code, what + ": " + status.error().message};
  }
  return made;
}

// The lookup itself (a query of PROJ's SQLite database and operation searches, tens of
// milliseconds); crs_from_proj_database keeps its results.
Result<Crs> lookup(int code, int vertical_code) {
  const std::string label = "EPSG:" + std::to_string(code) +
                            (vertical_code != 0 ? "+" + std::to_string(vertical_code) : "");
  Object crs = from_database(code, PJ_CATEGORY_CRS);
  if (!crs) {
    return Error{ErrorCode::Unsupported,
                 "EPSG:" + std::to_string(code) + " is not a CRS in PROJ's EPSG database"};
  }
  if (vertical_code != 0) {
    Object vertical = from_database(vertical_code, PJ_CATEGORY_CRS);
    if (!vertical || proj_get_type(vertical.p) != PJ_TYPE_VERTICAL_CRS) {
      return Error{ErrorCode::Unsupported, "EPSG:" + std::to_string(vertical_code) +
                                               " is not a vertical CRS in PROJ's EPSG database"};
    }
    const PJ_TYPE type = proj_get_type(crs.p);
    if (type != PJ_TYPE_PROJECTED_CRS && type != PJ_TYPE_GEOGRAPHIC_2D_CRS) {
      return Error{ErrorCode::Unsupported,
                   label + ": only a projected or geographic 2D CRS takes a vertical CRS"};
    }
    const std::string name =
        text_of(proj_get_name(crs.p)) + " + " + text_of(proj_get_name(vertical.p));
    Object compound(proj_create_compound_crs(context(), name.c_str(), crs.p, vertical.p));
    if (!compound) return Error{ErrorCode::Unsupported, label + ": " + proj_last_error()};
    return finish(crs_from_pj(compound.p, label), label, label);
  }
  return finish(crs_from_pj(crs.p, label), label, label);
}

// What PROJ made of a key, remembered for the process (PROJ's database is fixed for it).
template <typename Key, typename Value = Result<Crs>>
class Memo {
 public:
  template <typename Make>
  Value get(const Key& key, Make make) {
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      if (auto it = memo_.find(key); it != memo_.end()) return it->second;
    }
    Value found = make();
    const std::lock_guard<std::mutex> lock(mutex_);
    // The bound keeps hostile inputs (random codes, mutated WKT) from growing it without end.
    if (memo_.size() < kCapacity) memo_.emplace(key, found);
    return found;
  }

 private:
  static constexpr std::size_t kCapacity = 1024;
  std::mutex mutex_;
  std::map<Key, Value> memo_;
};

}  // namespace

Result<Crs> crs_from_proj_database(int code, int vertical_code) {
  static Memo<std::pair<int, int>> memo;
  return memo.get({code, vertical_code}, [&] { return lookup(code, vertical_code); });
}

Result<Crs> crs_from_proj_text(std::string_view text, const std::string& what) {
  constexpr std::size_t kMaxLength = 1 << 16;
  if (text.size() > kMaxLength) {
    return Error{ErrorCode::InvalidArgument,
                 what + " longer than " + std::to_string(kMaxLength) + " bytes"};
  }
  // LAS writers pad their WKT records with NULs (and spaces): those end the text.
  std::string owned(text);
  while (!owned.empty() && (owned.back() == '\0' || owned.back() == ' ' || owned.back() == '\n' ||
                            owned.back() == '\r' || owned.back() == '\t')) {
    owned.pop_back();
  }
  if (owned.empty()) return Error{ErrorCode::InvalidArgument, what + " is empty"};
  if (owned.find('\0') != std::string::npos) {
    return Error{ErrorCode::InvalidArgument, what + " contains a NUL byte"};
  }
  static Memo<std::pair<std::string, std::string>> memo;
  return memo.get({owned, what}, [&]() -> Result<Crs> {
    PJ_CONTEXT* ctx = context();
    Object crs;
    std::string why;
    const bool wkt = owned.find('[') != std::string::npos || owned.find('(') != std::string::npos;
    if (wkt && owned.front() != '{') {
      const char* options[] = {"STRICT=NO", nullptr};
      PROJ_STRING_LIST warnings = nullptr;
      PROJ_STRING_LIST errors = nullptr;
      crs = Object(proj_create_from_wkt(ctx, owned.c_str(), options, &warnings, &errors));
      for (auto list = errors; list != nullptr && *list != nullptr; ++list) {
        why += (why.empty() ? "" : "; ") + std::string(*list);
      }
      proj_string_list_destroy(warnings);
      proj_string_list_destroy(errors);
    } else {
      crs = Object(proj_create(ctx, owned.c_str()));
    }
    if (!crs) {
      // Text PROJ could not parse is malformed; parsed but unusable is unsupported.
      const bool malformed = !why.empty();
      if (why.empty()) why = proj_last_error();
      return Error{malformed ? ErrorCode::InvalidArgument : ErrorCode::Unsupported,
                   what + " is not a CRS PROJ can read" + (why.empty() ? "" : ": " + why)};
    }
    if (proj_is_crs(crs.p) == 0) {
      return Error{ErrorCode::Unsupported, what + " describes no CRS"};
    }
    return finish(crs_from_pj(crs.p, what), what + " (read by PROJ)", what);
  });
}

namespace {

// PROJ's one-line WKT 1 (GDAL dialect) of `object`; empty when PROJ cannot write it.
std::string wkt1_of(const Object& object) {
  if (!object) return std::string();
  const char* options[] = {"MULTILINE=NO", nullptr};
  return text_of(proj_as_wkt(context(), object.p, PJ_WKT1_GDAL, options));
}

}  // namespace

std::string proj_wkt1(const std::string& definition) {
  if (definition.empty()) return std::string();
  // Every cell of a run asks for the run's CRS again (its GeoPackage's spatial reference).
  static Memo<std::string, std::string> memo;
  return memo.get(definition,
                  [&] { return wkt1_of(Object(proj_create(context(), definition.c_str()))); });
}

std::string proj_horizontal_wkt1(const std::string& definition, int epsg) {
  if (epsg <= 0 && definition.empty()) return std::string();
  // Once per run and cell: PROJ writes WKT 1 of a definition without identifiers by looking
  // its names up (tens of milliseconds); from the database by code it is immediate.
  static Memo<std::pair<std::string, int>, std::string> memo;
  return memo.get({epsg > 0 ? std::string() : definition, epsg}, [&]() -> std::string {
    Object crs(epsg > 0 ? from_database(epsg, PJ_CATEGORY_CRS)
                        : Object(proj_create(context(), definition.c_str())));
    if (crs && proj_get_type(crs.p) == PJ_TYPE_COMPOUND_CRS) {
      return wkt1_of(Object(proj_crs_get_sub_crs(context(), crs.p, 0)));
    }
    return wkt1_of(crs);
  });
}

namespace {

// A unit of measure of PROJ's database by EPSG code and category ("linear", "angular"): its
// name and size in SI units; nullopt when the code is no unit of that category.
std::optional<std::pair<std::string, double>> unit_of(int code, std::string_view wanted) {
  const char* name = nullptr;
  double factor = 0.0;
  const char* category = nullptr;
  if (proj_uom_get_info_from_database(context(), "EPSG", std::to_string(code).c_str(), &name,
                                      &factor, &category) == 0 ||
      category == nullptr || std::string_view(category) != wanted || !(factor > 0)) {
    return std::nullopt;
  }
  return std::pair<std::string, double>(text_of(name), factor);
}

}  // namespace

std::optional<LinearUnit> linear_unit_from_epsg(int code) {
  const auto found = unit_of(code, "linear");
  if (!found) return std::nullopt;
  LinearUnit unit = linear_unit_from_size(found->first, found->second);
  unit.epsg = code;
  return unit;
}

std::optional<AngularUnit> angular_unit_from_epsg(int code) {
  const auto found = unit_of(code, "angular");
  if (!found) return std::nullopt;
  AngularUnit unit = angular_unit_from_size(found->first, found->second);
  unit.epsg = code;
  return unit;
}

std::optional<Ellipsoid> ellipsoid_from_epsg(int code) {
  Object e = from_database(code, PJ_CATEGORY_ELLIPSOID);
  double a = 0, b = 0, rf = 0;
  int computed = 0;
  if (!e || proj_ellipsoid_get_parameters(context(), e.p, &a, &b, &computed, &rf) == 0) {
    return std::nullopt;
  }
  Ellipsoid out;
  out.name = text_of(proj_get_name(e.p));
  out.epsg = code;
  out.semi_major_m = a;
  out.inverse_flattening = a == b ? 0.0 : rf;
  return out;
}

std::optional<double> prime_meridian_from_epsg(int code) {
  Object pm = from_database(code, PJ_CATEGORY_PRIME_MERIDIAN);
  double longitude = 0, unit = 0;
  if (!pm || proj_prime_meridian_get_parameters(context(), pm.p, &longitude, &unit, nullptr) == 0) {
    return std::nullopt;
  }
  return longitude * unit / kDegree;
}

int geographic_crs_of_datum(int datum_code) {
  PJ_OBJ_LIST* list = proj_query_geodetic_crs_from_datum(
      context(), "EPSG", "EPSG", std::to_string(datum_code).c_str(), "geographic 2D");
  if (list == nullptr) return 0;
  int best = 0;
  const int n = proj_list_get_count(list);
  for (int i = 0; i < n; ++i) {
    Object crs(proj_list_get(context(), list, i));
    const int code = crs ? epsg_of(crs.p) : 0;
    if (code != 0 && (best == 0 || code < best)) best = code;  // the oldest code: the datum's own
  }
  proj_list_destroy(list);
  return best;
}

std::optional<GeodeticDatum> datum_from_epsg(int code) {
  const int geographic = geographic_crs_of_datum(code);
  if (geographic == 0) return std::nullopt;
  auto crs = crs_from_proj_database(geographic, 0);
  if (!crs.ok()) return std::nullopt;
  return crs.value().datum;
}

std::optional<GeodeticDatum> datum_from_name(std::string_view name) {
  std::string query(name);
  if (query.rfind("D_", 0) == 0) query.erase(0, 2);
  for (char& c : query) c = c == '_' ? ' ' : c;
  auto key = [](std::string_view text) {
    std::string k = normalise_name(text);
    for (const char* noise : {"datum", "geodetic"}) {
      if (const auto at = k.find(noise); at != std::string::npos) k.erase(at, std::strlen(noise));
    }
    return k;
  };
  const std::string wanted = key(query);
  if (wanted.empty()) return std::nullopt;
  const PJ_TYPE types[] = {PJ_TYPE_GEODETIC_REFERENCE_FRAME};
  PJ_OBJ_LIST* list =
      proj_create_from_name(context(), "EPSG", query.c_str(), types, 1, 1, 20, nullptr);
  if (list == nullptr) return std::nullopt;
  int code = 0;
  const int n = proj_list_get_count(list);
  for (int i = 0; i < n && code == 0; ++i) {
    Object datum(proj_list_get(context(), list, i));
    if (datum && key(text_of(proj_get_name(datum.p))) == wanted) code = epsg_of(datum.p);
  }
  proj_list_destroy(list);
  return code != 0 ? datum_from_epsg(code) : std::nullopt;
}

std::optional<VerticalCrs> vertical_from_epsg(int code) {
  Object crs = from_database(code, PJ_CATEGORY_CRS);
  std::vector<std::string> ignored;
  auto v = crs ? vertical_of(crs.p, nullptr, ignored) : std::nullopt;
  if (v) v->epsg = code;
  return v;
}

void settle_vertical(Crs& crs) {
  if (!crs.vertical || crs.vertical->epsg == 0 || crs.definition.empty()) return;
  PJ_CONTEXT* ctx = context();
  Object horizontal(proj_create(ctx, crs.definition.c_str()));
  Object vertical = from_database(crs.vertical->epsg, PJ_CATEGORY_CRS);
  if (!horizontal || !vertical || proj_get_type(vertical.p) != PJ_TYPE_VERTICAL_CRS) return;
  Object source;
  settle_geoid(unbound(horizontal.p, source), vertical.p, *crs.vertical, crs.warnings);
  const std::string name = crs.name + " + " + crs.vertical->name;
  Object compound(proj_create_compound_crs(ctx, name.c_str(), horizontal.p, vertical.p));
  if (compound) crs.definition = definition_of(compound.p);
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
