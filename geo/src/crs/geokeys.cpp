// CRS from GeoTIFF keys (GeoTIFF 1.0 / OGC GeoTIFF 1.1 key ids), as LAS files carry them.
//
// The keys are mapped for PROJ, as libgeotiff normalises them: an EPSG code is read from
// PROJ's database; user-defined parts are assembled from the individual keys (datum, ellipsoid,
// prime meridian and units from PROJ's database by their codes) into a PROJ string, with the
// usual fallbacks between "natural origin", "false origin" and "center" parameter keys that
// writers mix up. Projection parameters are in the GeogAngularUnits (angles) and
// ProjLinearUnits (lengths), per the specification.

#include <cmath>
#include <map>
#include <set>
#include <string>

#include "crs/crs_internal.h"
#include "crs/geodesy.h"

namespace csgtile::geo {
namespace {

using kernel::Error;
using kernel::ErrorCode;
using kernel::Result;

constexpr int kUserDefined = 32767;

enum Key : std::uint16_t {
  GTModelType = 1024,
  GTRasterType = 1025,
  GTCitation = 1026,
  GeographicType = 2048,
  GeogCitation = 2049,
  GeogGeodeticDatum = 2050,
  GeogPrimeMeridian = 2051,
  GeogLinearUnits = 2052,
  GeogLinearUnitSize = 2053,
  GeogAngularUnits = 2054,
  GeogAngularUnitSize = 2055,
  GeogEllipsoid = 2056,
  GeogSemiMajorAxis = 2057,
  GeogSemiMinorAxis = 2058,
  GeogInvFlattening = 2059,
  GeogAzimuthUnits = 2060,
  GeogPrimeMeridianLong = 2061,
  GeogTOWGS84 = 2062,
  ProjectedCSType = 3072,
  PCSCitation = 3073,
  ProjectionCode = 3074,
  ProjCoordTrans = 3075,
  ProjLinearUnits = 3076,
  ProjLinearUnitSize = 3077,
  ProjStdParallel1 = 3078,
  ProjStdParallel2 = 3079,
  ProjNatOriginLong = 3080,
  ProjNatOriginLat = 3081,
  ProjFalseEasting = 3082,
  ProjFalseNorthing = 3083,
  ProjFalseOriginLong = 3084,
  ProjFalseOriginLat = 3085,
  ProjFalseOriginEasting = 3086,
  ProjFalseOriginNorthing = 3087,
  ProjCenterLong = 3088,
  ProjCenterLat = 3089,
  ProjCenterEasting = 3090,
  ProjCenterNorthing = 3091,
  ProjScaleAtNatOrigin = 3092,
  ProjScaleAtCenter = 3093,
  ProjAzimuthAngle = 3094,
  ProjStraightVertPoleLong = 3095,
  VerticalCSType = 4096,
  VerticalCitation = 4097,
  VerticalDatum = 4098,
  VerticalUnits = 4099,
};

bool is_known_key(std::uint16_t id) {
  return (id >= 1024 && id <= 1026) || (id >= 2048 && id <= 2062) || (id >= 3072 && id <= 3095) ||
         (id >= 4096 && id <= 4099);
}

class Keys {
 public:
  explicit Keys(const std::vector<GeoKeyEntry>& entries, std::vector<std::string>& warnings) {
    std::set<std::uint16_t> unknown;
    int zero = 0;
    for (const GeoKeyEntry& e : entries) {
      if (e.id == 0) {
        ++zero;
        continue;
      }
      if (!is_known_key(e.id)) {
        unknown.insert(e.id);
        continue;
      }
      if (by_id_.count(e.id))
        warnings.push_back("GeoKey " + std::to_string(e.id) + " repeated: the last one is used");
      by_id_[e.id] = &e;
    }
    if (zero)
      warnings.push_back(std::to_string(zero) + " GeoKey entr" + (zero == 1 ? "y" : "ies") +
                         " with id 0 ignored");
    if (!unknown.empty()) {
      std::string list;
      for (auto id : unknown) list += (list.empty() ? "" : ", ") + std::to_string(id);
      warnings.push_back("unknown GeoKeys ignored: " + list);
    }
  }

  bool has(std::uint16_t id) const { return by_id_.count(id) != 0; }

  /// A SHORT key's value; nullopt when absent. Errors when present but not a small integer.
  Result<std::optional<int>> code(std::uint16_t id) const {
    auto it = by_id_.find(id);
    if (it == by_id_.end()) return std::optional<int>{};
    const auto& n = it->second->numbers;
    if (n.empty() || !std::isfinite(n[0]) || n[0] < 0 || n[0] > 65535 || n[0] != std::floor(n[0])) {
      return Error{ErrorCode::InvalidArgument,
                   "GeoKey " + std::to_string(id) + " must hold one integer code"};
    }
    return std::optional<int>(static_cast<int>(n[0]));
  }

  std::optional<double> number(std::uint16_t id) const {
    auto it = by_id_.find(id);
    if (it == by_id_.end() || it->second->numbers.empty()) return std::nullopt;
    return it->second->numbers[0];
  }

  const std::vector<double>* numbers(std::uint16_t id) const {
    auto it = by_id_.find(id);
    return it == by_id_.end() ? nullptr : &it->second->numbers;
  }

  std::string text(std::uint16_t id) const {
    auto it = by_id_.find(id);
    if (it == by_id_.end()) return {};
    std::string s = it->second->text;
    while (!s.empty() && (s.back() == '|' || s.back() == '\0' || s.back() == ' ')) s.pop_back();
    return s;
  }

  /// First present of several keys.
  std::optional<double> first(std::initializer_list<std::uint16_t> ids) const {
    for (auto id : ids) {
      if (auto v = number(id)) return v;
    }
    return std::nullopt;
  }

 private:
  std::map<std::uint16_t, const GeoKeyEntry*> by_id_;
};

Error key_error(ErrorCode code, std::string message) { return Error{code, std::move(message)}; }

// "GCS Name = GCS_North_American_1983|Datum = D_North_American_1983|..." → the named field.
std::string citation_field(const std::string& citation, const std::string& field) {
  const auto at = citation.find(field + " = ");
  if (at == std::string::npos) return {};
  const auto start = at + field.size() + 3;
  const auto end = citation.find('|', start);
  return citation.substr(start, end == std::string::npos ? std::string::npos : end - start);
}

Result<AngularUnit> angular_unit(const Keys& keys) {
  auto code = keys.code(GeogAngularUnits);
  if (!code.ok()) return code.error();
  if (!code.value() || *code.value() == 0) return degree_unit();
  if (*code.value() == kUserDefined) {
    auto size = keys.number(GeogAngularUnitSize);
    if (!size || !(*size > 0)) {
      return key_error(ErrorCode::InvalidArgument,
                       "user-defined GeogAngularUnitsGeoKey (2054) without a positive "
                       "GeogAngularUnitSizeGeoKey (2055)");
    }
    return detail::angular_unit_from_size("user-defined angle", *size);
  }
  if (auto unit = detail::angular_unit_from_epsg(*code.value())) return *unit;
  return key_error(ErrorCode::Unsupported, "GeogAngularUnitsGeoKey (2054) unit EPSG:" +
                                               std::to_string(*code.value()) + " is not supported");
}

Result<LinearUnit> linear_unit(const Keys& keys, std::uint16_t code_key, std::uint16_t size_key,
                               const char* what) {
  auto code = keys.code(code_key);
  if (!code.ok()) return code.error();
  if (!code.value()) return metre_unit();
  if (*code.value() == kUserDefined) {
    auto size = keys.number(size_key);
    if (!size || !(*size > 0) || !std::isfinite(*size)) {
      return key_error(ErrorCode::InvalidArgument,
                       std::string("user-defined ") + what + " (" + std::to_string(code_key) +
                           ") without a positive unit size (" + std::to_string(size_key) + ")");
    }
    return detail::linear_unit_from_size("user-defined length", *size);
  }
  if (auto unit = detail::linear_unit_from_epsg(*code.value())) {
    // A size key beside a known code must agree; writers add it for readers without tables.
    if (auto size = keys.number(size_key);
        size && std::fabs(*size - unit->metres) > 1e-9 * unit->metres) {
      return key_error(ErrorCode::InvalidArgument,
                       std::string(what) + " EPSG:" + std::to_string(*code.value()) + " (" +
                           detail::format_number(unit->metres) + " m) contradicts its size key " +
                           std::to_string(size_key) + " (" + detail::format_number(*size) + " m)");
    }
    return *unit;
  }
  return key_error(ErrorCode::Unsupported, std::string(what) + " (" + std::to_string(code_key) +
                                               ") unit EPSG:" + std::to_string(*code.value()) +
                                               " is not supported");
}

// A geographic CRS from keys 2048-2062 (EPSG or user-defined).
Result<Crs> geographic_from_keys(const Keys& keys, std::vector<std::string>& warnings) {
  auto code = keys.code(GeographicType);
  if (!code.ok()) return code.error();
  auto unit = angular_unit(keys);
  if (!unit.ok()) return unit.error();
  auto datum_code = keys.code(GeogGeodeticDatum);
  if (!datum_code.ok()) return datum_code.error();
  auto ellipsoid_code = keys.code(GeogEllipsoid);
  if (!ellipsoid_code.ok()) return ellipsoid_code.error();

  Crs crs;
  crs.kind = CrsKind::Geographic;
  crs.angular_unit = unit.value();
  crs.source = "GeoTIFF keys";
  const std::string citation = keys.text(GeogCitation);

  if (code.value() && *code.value() != kUserDefined && *code.value() != 0) {
    auto known = crs_from_epsg(*code.value());
    if (!known.ok() || known.value().kind != CrsKind::Geographic) {
      return key_error(ErrorCode::Unsupported,
                       "GeographicTypeGeoKey (2048) EPSG:" + std::to_string(*code.value()) +
                           " is not a geographic CRS in PROJ's EPSG database");
    }
    crs = known.value();
    crs.angular_unit = unit.value();
    crs.source = "GeoTIFF keys";
    // Redundant ellipsoid keys (writers add them) must agree with the code.
    if (auto a = keys.number(GeogSemiMajorAxis);
        a && std::fabs(*a - crs.datum.ellipsoid.semi_major_m) > 1e-3) {
      warnings.push_back("GeogSemiMajorAxisGeoKey (2057) " + detail::format_number(*a) +
                         " disagrees with EPSG:" + std::to_string(crs.epsg) + " (" +
                         detail::format_number(crs.datum.ellipsoid.semi_major_m) +
                         "); using the EPSG code");
    }
  } else {
    // User-defined: datum, ellipsoid and prime meridian from their own keys.
    GeodeticDatum datum;
    bool datum_known = false;
    if (datum_code.value() && *datum_code.value() != kUserDefined && *datum_code.value() != 0) {
      if (auto d = detail::datum_from_epsg(*datum_code.value())) {
        datum = *d;
        datum_known = true;
      } else {
        warnings.push_back(
            "GeogGeodeticDatumGeoKey (2050) EPSG:" + std::to_string(*datum_code.value()) +
            " is not a datum of PROJ's EPSG database: using the ellipsoid keys");
      }
    }
    std::string datum_name = citation_field(citation, "Datum");
    if (!datum_known) {
      datum.epsg = 0;
      datum.name = datum_name.empty() ? "unknown" : datum_name;
    }
    // Ellipsoid: a code, or the axis keys; a known datum supplies one too.
    std::optional<Ellipsoid> ellipsoid;
    if (ellipsoid_code.value() && *ellipsoid_code.value() != kUserDefined &&
        *ellipsoid_code.value() != 0) {
      ellipsoid = detail::ellipsoid_from_epsg(*ellipsoid_code.value());
      if (!ellipsoid) {
        if (!keys.has(GeogSemiMajorAxis)) {
          return key_error(ErrorCode::Unsupported, "GeogEllipsoidGeoKey (2056) EPSG:" +
                                                       std::to_string(*ellipsoid_code.value()) +
                                                       " is not an ellipsoid of PROJ's database");
        }
      }
    }
    if (!ellipsoid && keys.has(GeogSemiMajorAxis)) {
      const double a = *keys.number(GeogSemiMajorAxis);
      double rf = 0.0;
      if (auto inv = keys.number(GeogInvFlattening)) {
        rf = *inv;
      } else if (auto b = keys.number(GeogSemiMinorAxis)) {
        rf = (*b == a) ? 0.0 : a / (a - *b);
      } else {
        return key_error(ErrorCode::InvalidArgument,
                         "GeogSemiMajorAxisGeoKey (2057) without GeogInvFlatteningGeoKey (2059) or "
                         "GeogSemiMinorAxisGeoKey (2058)");
      }
      Ellipsoid e;
      const std::string ell_name = citation_field(citation, "Ellipsoid");
      e.name = ell_name.empty() ? "user-defined" : ell_name;
      e.epsg = 0;
      e.semi_major_m = a;
      e.inverse_flattening = rf;
      for (int known : {7030, 7019, 7004, 7001, 7008, 7022}) {
        const auto found = detail::ellipsoid_from_epsg(known);
        if (!found) continue;
        const Ellipsoid& k = *found;
        if (std::fabs(k.semi_major_m - a) < 1e-6 && std::fabs(k.inverse_flattening - rf) < 1e-8) {
          e.epsg = k.epsg;
          if (ell_name.empty()) e.name = k.name;
        }
      }
      ellipsoid = e;
    }
    if (!ellipsoid && datum_known) ellipsoid = datum.ellipsoid;
    if (!ellipsoid) {
      return key_error(
          ErrorCode::InvalidArgument,
          "user-defined geographic CRS without an ellipsoid (GeoKeys 2050, 2056-2059)");
    }
    if (datum_known && std::fabs(datum.ellipsoid.semi_major_m - ellipsoid->semi_major_m) > 1e-3) {
      warnings.push_back("ellipsoid keys disagree with datum EPSG:" + std::to_string(datum.epsg) +
                         "; using the ellipsoid keys");
    }
    datum.ellipsoid = *ellipsoid;
    if (!datum_known) {
      // Name a datum we know and whose ellipsoid matches; else only WGS 84 / GRS 80 datums are
      // assumed equal to WGS 84 (as PROJ's ballpark does), with a warning.
      auto named = detail::datum_from_name(datum_name.empty() ? citation : datum_name);
      if (named && std::fabs(named->ellipsoid.semi_major_m - ellipsoid->semi_major_m) < 1e-3 &&
          named->to_wgs84) {
        datum.to_wgs84 = named->to_wgs84;
        datum.to_wgs84_source = named->to_wgs84_source;
        datum.name = named->name;
        datum.epsg = named->epsg;
      } else if (ellipsoid->semi_major_m == 6378137.0 &&
                 std::fabs(ellipsoid->inverse_flattening - 298.2572) < 1e-3) {
        datum.to_wgs84 = Helmert7{};
        datum.to_wgs84_source = "assumed null (user-defined datum on a WGS 84/GRS 80 ellipsoid)";
        if (!keys.has(GeogTOWGS84)) {
          warnings.push_back("user-defined datum '" + datum.name + "' on the " + ellipsoid->name +
                             " ellipsoid assumed equal to WGS 84");
        }
      } else {
        datum.to_wgs84 = std::nullopt;
        datum.to_wgs84_source = "unknown";
        if (!keys.has(GeogTOWGS84)) {
          warnings.push_back("user-defined datum '" + datum.name +
                             "' has no TOWGS84 (GeoKey 2062): it cannot be placed on the globe");
        }
      }
    }
    // Prime meridian.
    auto pm = keys.code(GeogPrimeMeridian);
    if (!pm.ok()) return pm.error();
    if (pm.value() && *pm.value() != kUserDefined && *pm.value() != 0) {
      const auto longitude = detail::prime_meridian_from_epsg(*pm.value());
      if (!longitude) {
        return key_error(ErrorCode::Unsupported,
                         "GeogPrimeMeridianGeoKey (2051) EPSG:" + std::to_string(*pm.value()) +
                             " is not a prime meridian of PROJ's database");
      }
      datum.prime_meridian_deg = *longitude;
    } else if (auto pm_long = keys.number(GeogPrimeMeridianLong)) {
      datum.prime_meridian_deg = *pm_long * unit.value().radians / detail::kDegree;
    }
    crs.datum = datum;
    const std::string gcs_name = citation_field(citation, "GCS Name");
    crs.name = !gcs_name.empty()
                   ? gcs_name
                   : (!citation.empty() && citation.find('=') == std::string::npos ? citation
                                                                                   : datum.name);
    crs.epsg = 0;
  }
  // An explicit TOWGS84 key wins over the table (the writer said so).
  if (const auto* t = keys.numbers(GeogTOWGS84)) {
    if (t->size() != 3 && t->size() != 7) {
      return key_error(
          ErrorCode::InvalidArgument,
          "GeogTOWGS84GeoKey (2062) must hold 3 or 7 values, has " + std::to_string(t->size()));
    }
    const auto v = [&](std::size_t i) { return i < t->size() ? (*t)[i] : 0.0; };
    Helmert7 h = detail::helmert_from_position_vector(v(0), v(1), v(2), v(3), v(4), v(5), v(6));
    if (crs.datum.to_wgs84 && !crs.datum.to_wgs84->is_null() && h.is_null()) {
      warnings.push_back("GeogTOWGS84GeoKey (2062) is null but datum '" + crs.datum.name +
                         "' has a known shift (" + crs.datum.to_wgs84_source + "); using the key");
    }
    crs.datum.to_wgs84 = h;
    crs.datum.to_wgs84_source = "GeogTOWGS84GeoKey (2062)";
  }
  return crs;
}

Result<std::optional<VerticalCrs>> vertical_from_keys(const Keys& keys,
                                                      std::vector<std::string>& warnings) {
  auto code = keys.code(VerticalCSType);
  if (!code.ok()) return code.error();
  const bool has_unit = keys.has(VerticalUnits);
  std::optional<LinearUnit> unit;
  if (has_unit) {
    auto u = keys.code(VerticalUnits);
    if (!u.ok()) return u.error();
    unit = detail::linear_unit_from_epsg(*u.value());
    if (!unit) {
      return key_error(ErrorCode::Unsupported,
                       "VerticalUnitsGeoKey (4099) unit EPSG:" + std::to_string(*u.value()) +
                           " is not supported");
    }
  }
  const std::string citation = keys.text(VerticalCitation);
  if (!code.value() || *code.value() == 0 || *code.value() == kUserDefined) {
    if (!has_unit && citation.empty()) return std::optional<VerticalCrs>{};
    VerticalCrs v{0, citation.empty() ? "user-defined vertical CRS" : citation,
                  unit.value_or(metre_unit())};
    return std::optional<VerticalCrs>(v);
  }
  auto known = detail::vertical_from_epsg(*code.value());
  VerticalCrs v =
      known ? *known
            : VerticalCrs{*code.value(),
                          citation.empty() ? "EPSG:" + std::to_string(*code.value()) : citation,
                          unit.value_or(metre_unit())};
  if (!known && !has_unit) {
    warnings.push_back(
        "vertical CRS EPSG:" + std::to_string(*code.value()) +
        " is not a vertical CRS of PROJ's EPSG database and VerticalUnitsGeoKey (4099) is "
        "absent: metre assumed");
  }
  if (known && unit && std::fabs(unit->metres - known->unit.metres) > 1e-12) {
    warnings.push_back("VerticalUnitsGeoKey (4099) " + unit->name +
                       " differs from the unit of EPSG:" + std::to_string(known->epsg) + " (" +
                       known->unit.name + "); using the key");
    v.unit = *unit;
  }
  return std::optional<VerticalCrs>(v);
}

// The user-defined projection of keys 3075 + 3078..3095, in degrees and metres.
Result<Projection> projection_from_keys(const Keys& keys, const AngularUnit& angle,
                                        const LinearUnit& length,
                                        std::vector<std::string>& warnings) {
  auto method = keys.code(ProjCoordTrans);
  if (!method.ok()) return method.error();
  const double to_deg = angle.radians / detail::kDegree;
  const double to_m = length.metres;
  auto deg = [&](std::initializer_list<std::uint16_t> ids) -> std::optional<double> {
    auto v = keys.first(ids);
    return v ? std::optional<double>(*v * to_deg) : std::nullopt;
  };
  auto metres = [&](std::initializer_list<std::uint16_t> ids) {
    return keys.first(ids).value_or(0.0) * to_m;
  };
  auto origin = [&](std::initializer_list<std::uint16_t> ids, const char* what) {
    auto v = deg(ids);
    if (!v) warnings.push_back(std::string("GeoTIFF projection: ") + what + " absent, 0 assumed");
    return v.value_or(0.0);
  };
  Projection p;
  const int ct = *method.value();
  auto n = [](double v) { return detail::format_number(v); };
  switch (ct) {
    case 1:    // CT_TransverseMercator
    case 16:   // CT_ObliqueStereographic
    case 9: {  // CT_LambertConfConic_1SP
      if (ct == 9 && !keys.first({ProjNatOriginLat, ProjCenterLat, ProjFalseOriginLat})) {
        return key_error(ErrorCode::InvalidArgument,
                         "ProjCoordTransGeoKey 9 (LCC 1SP) needs ProjNatOriginLatGeoKey (3081)");
      }
      const double lat0 =
          origin({ProjNatOriginLat, ProjCenterLat, ProjFalseOriginLat}, "latitude of origin");
      const double lon0 =
          origin({ProjNatOriginLong, ProjCenterLong, ProjFalseOriginLong}, "longitude of origin");
      const double k = keys.first({ProjScaleAtNatOrigin, ProjScaleAtCenter}).value_or(1.0);
      const double fe = metres({ProjFalseEasting, ProjCenterEasting, ProjFalseOriginEasting});
      const double fn = metres({ProjFalseNorthing, ProjCenterNorthing, ProjFalseOriginNorthing});
      const std::string rest =
          " +lon_0=" + n(lon0) + " +k_0=" + n(k) + " +x_0=" + n(fe) + " +y_0=" + n(fn);
      if (ct == 1) {
        p.method_name = "Transverse Mercator";
        p.proj_string = "+proj=tmerc +lat_0=" + n(lat0) + rest;
      } else if (ct == 16) {
        p.method_name = "Oblique Stereographic";
        p.proj_string = "+proj=sterea +lat_0=" + n(lat0) + rest;
      } else {
        p.method_name = "Lambert Conic Conformal (1SP)";
        p.proj_string = "+proj=lcc +lat_1=" + n(lat0) + " +lat_0=" + n(lat0) + rest;
      }
      break;
    }
    case 8: {  // CT_LambertConfConic_2SP
      auto sp1 = deg({ProjStdParallel1});
      auto sp2 = deg({ProjStdParallel2});
      if (!sp1 || !sp2) {
        return key_error(ErrorCode::InvalidArgument,
                         "ProjCoordTransGeoKey 8 (LCC 2SP) needs ProjStdParallel1GeoKey (3078) and "
                         "ProjStdParallel2GeoKey (3079)");
      }
      const double lat0 =
          origin({ProjFalseOriginLat, ProjNatOriginLat, ProjCenterLat}, "latitude of false origin");
      const double lon0 = origin({ProjFalseOriginLong, ProjNatOriginLong, ProjCenterLong},
                                 "longitude of false origin");
      const double fe = metres({ProjFalseOriginEasting, ProjFalseEasting, ProjCenterEasting});
      const double fn = metres({ProjFalseOriginNorthing, ProjFalseNorthing, ProjCenterNorthing});
      p.method_name = "Lambert Conic Conformal (2SP)";
      p.proj_string = "+proj=lcc +lat_1=" + n(*sp1) + " +lat_2=" + n(*sp2) + " +lat_0=" + n(lat0) +
                      " +lon_0=" + n(lon0) + " +x_0=" + n(fe) + " +y_0=" + n(fn);
      break;
    }
    case 15: {  // CT_PolarStereographic: |latitude| = 90 → variant A, else the standard parallel
                // (B)
      const double lat = origin({ProjNatOriginLat, ProjCenterLat}, "latitude of origin");
      const double lon0 = origin({ProjStraightVertPoleLong, ProjNatOriginLong, ProjCenterLong},
                                 "longitude of origin");
      const double fe = metres({ProjFalseEasting, ProjCenterEasting, ProjFalseOriginEasting});
      const double fn = metres({ProjFalseNorthing, ProjCenterNorthing, ProjFalseOriginNorthing});
      const double k = keys.first({ProjScaleAtNatOrigin, ProjScaleAtCenter}).value_or(1.0);
      const std::string rest = " +lon_0=" + n(lon0) + " +x_0=" + n(fe) + " +y_0=" + n(fn);
      if (std::fabs(lat) == 90.0) {
        p.method_name = "Polar Stereographic (variant A)";
        p.proj_string = "+proj=stere +lat_0=" + n(lat) + " +k_0=" + n(k) + rest;
      } else {
        if (lat == 0.0) {
          return key_error(ErrorCode::InvalidArgument,
                           "ProjCoordTransGeoKey 15 (polar stereographic): the standard parallel "
                           "must lie strictly between the equator and the pole");
        }
        p.method_name = "Polar Stereographic (variant B)";
        p.proj_string =
            "+proj=stere +lat_0=" + n(lat < 0 ? -90.0 : 90.0) + " +lat_ts=" + n(lat) + rest;
        if (k != 1.0) {
          warnings.push_back("polar stereographic with latitude " + detail::format_number(lat) +
                             " read as variant B (standard parallel); its scale factor " +
                             detail::format_number(k) + " is ignored");
        }
      }
      break;
    }
    case 7:     // CT_Mercator (1SP with a scale, or 2SP with a standard parallel)
    case 10:    // CT_LambertAzimEqualArea
    case 11:    // CT_AlbersEqualArea
    case 12:    // CT_AzimuthalEquidistant
    case 14:    // CT_Stereographic
    case 17:    // CT_Equirectangular
    case 18:    // CT_CassiniSoldner
    case 22:    // CT_Polyconic
    case 24: {  // CT_Sinusoidal
      // The ellipsoid is the datum's, added where the projection is computed.
      const double lat0 = deg({ProjNatOriginLat, ProjCenterLat, ProjFalseOriginLat}).value_or(0.0);
      const double lon0 =
          deg({ProjNatOriginLong, ProjCenterLong, ProjFalseOriginLong}).value_or(0.0);
      const double fe = metres({ProjFalseEasting, ProjCenterEasting, ProjFalseOriginEasting});
      const double fn = metres({ProjFalseNorthing, ProjCenterNorthing, ProjFalseOriginNorthing});
      const std::string common = " +lon_0=" + n(lon0) + " +x_0=" + n(fe) + " +y_0=" + n(fn);
      std::string text;
      switch (ct) {
        case 7:
          if (auto sp1 = deg({ProjStdParallel1})) {
            text = "+proj=merc +lat_ts=" + n(*sp1) + common;
          } else {
            text = "+proj=merc +k_0=" +
                   n(keys.first({ProjScaleAtNatOrigin, ProjScaleAtCenter}).value_or(1.0)) + common;
          }
          p.method_name = "Mercator";
          break;
        case 10:
          text = "+proj=laea +lat_0=" + n(lat0) + common;
          p.method_name = "Lambert Azimuthal Equal Area";
          break;
        case 11: {
          auto sp1 = deg({ProjStdParallel1});
          auto sp2 = deg({ProjStdParallel2});
          if (!sp1 || !sp2) {
            return key_error(ErrorCode::InvalidArgument,
                             "ProjCoordTransGeoKey 11 (Albers) needs ProjStdParallel1GeoKey "
                             "(3078) and ProjStdParallel2GeoKey (3079)");
          }
          text =
              "+proj=aea +lat_1=" + n(*sp1) + " +lat_2=" + n(*sp2) + " +lat_0=" + n(lat0) + common;
          p.method_name = "Albers Equal Area";
          break;
        }
        case 12:
          text = "+proj=aeqd +lat_0=" + n(lat0) + common;
          p.method_name = "Azimuthal Equidistant";
          break;
        case 14:
          text = "+proj=stere +lat_0=" + n(lat0) +
                 " +k_0=" + n(keys.first({ProjScaleAtNatOrigin, ProjScaleAtCenter}).value_or(1.0)) +
                 common;
          p.method_name = "Stereographic";
          break;
        case 17:
          text = "+proj=eqc +lat_ts=" + n(deg({ProjStdParallel1}).value_or(lat0)) + common;
          p.method_name = "Equidistant Cylindrical";
          break;
        case 18:
          text = "+proj=cass +lat_0=" + n(lat0) + common;
          p.method_name = "Cassini-Soldner";
          break;
        case 22:
          text = "+proj=poly +lat_0=" + n(lat0) + common;
          p.method_name = "American Polyconic";
          break;
        default:
          text = "+proj=sinu" + common;
          p.method_name = "Sinusoidal";
          break;
      }
      p.proj_string = text;
      break;
    }
    default: {
      static const char* const names[] = {"",
                                          "TransverseMercator",
                                          "TransvMercator_Modified_Alaska",
                                          "ObliqueMercator",
                                          "ObliqueMercator_Laborde",
                                          "ObliqueMercator_Rosenmund",
                                          "ObliqueMercator_Spherical",
                                          "Mercator",
                                          "LambertConfConic_2SP",
                                          "LambertConfConic_1SP",
                                          "LambertAzimEqualArea",
                                          "AlbersEqualArea",
                                          "AzimuthalEquidistant",
                                          "EquidistantConic",
                                          "Stereographic",
                                          "PolarStereographic",
                                          "ObliqueStereographic",
                                          "Equirectangular",
                                          "CassiniSoldner",
                                          "Gnomonic",
                                          "MillerCylindrical",
                                          "Orthographic",
                                          "Polyconic",
                                          "Robinson",
                                          "Sinusoidal",
                                          "VanDerGrinten",
                                          "NewZealandMapGrid",
                                          "TransvMercator_SouthOriented"};
      const std::string name =
          ct > 0 && ct < 28 ? std::string(" (CT_") + names[ct] + ")" : std::string();
      return key_error(ErrorCode::Unsupported,
                       "ProjCoordTransGeoKey (3075) method " + std::to_string(ct) + name +
                           " is not supported (supported: 1 TM, 7 Mercator, 8 LCC 2SP, 9 LCC 1SP, "
                           "10 LAEA, 11 Albers, 12 azimuthal equidistant, 14 stereographic, 15 "
                           "polar stereographic, 16 oblique stereographic, 17 equirectangular, 18 "
                           "Cassini-Soldner, 22 polyconic, 24 sinusoidal)");
    }
  }
  return p;
}

Projection utm_projection(int zone, bool north) {
  Projection p;
  p.method_name = "Transverse Mercator";
  p.proj_string = "+proj=utm +zone=" + std::to_string(zone) + (north ? "" : " +south");
  return p;
}

Result<Crs> projected_from_keys(const Keys& keys, std::vector<std::string>& warnings) {
  auto code = keys.code(ProjectedCSType);
  if (!code.ok()) return code.error();
  auto projection_code = keys.code(ProjectionCode);
  if (!projection_code.ok()) return projection_code.error();
  const bool user_projection = keys.has(ProjCoordTrans);
  const std::string citation =
      keys.text(PCSCitation).empty() ? keys.text(GTCitation) : keys.text(PCSCitation);

  std::optional<LinearUnit> key_unit;
  if (keys.has(ProjLinearUnits)) {
    auto u = linear_unit(keys, ProjLinearUnits, ProjLinearUnitSize, "ProjLinearUnitsGeoKey");
    if (!u.ok()) return u.error();
    key_unit = u.value();
  }

  if (code.value() && *code.value() != kUserDefined && *code.value() != 0) {
    auto known = crs_from_epsg(*code.value());
    if (known.ok() && known.value().is_projected()) {
      Crs crs = known.value();
      crs.source = "GeoTIFF keys";
      if (key_unit &&
          std::fabs(key_unit->metres - crs.linear_unit.metres) > 1e-12 * crs.linear_unit.metres) {
        warnings.push_back("ProjLinearUnitsGeoKey (3076) " + key_unit->name +
                           " overrides the unit of EPSG:" + std::to_string(crs.epsg) + " (" +
                           crs.linear_unit.name + "): coordinates are read in " + key_unit->name);
        crs.linear_unit = *key_unit;
        crs.definition.clear();  // no longer EPSG's: rewritten from the model
      }
      if (auto g = keys.code(GeographicType);
          g.ok() && g.value() && *g.value() != kUserDefined && *g.value() != 0) {
        auto geog = crs_from_epsg(*g.value());
        if (geog.ok() && std::fabs(geog.value().datum.ellipsoid.semi_major_m -
                                   crs.datum.ellipsoid.semi_major_m) > 1e-3) {
          warnings.push_back("GeographicTypeGeoKey (2048) EPSG:" + std::to_string(*g.value()) +
                             " disagrees with the datum of EPSG:" + std::to_string(crs.epsg) +
                             "; using EPSG:" + std::to_string(crs.epsg));
        }
      }
      if (user_projection) {
        std::vector<std::string> ignored;
        auto p = projection_from_keys(keys, degree_unit(), crs.linear_unit, ignored);
        if (p.ok()) {
          Crs other = crs;
          other.projection = p.value();
          if (auto diff = crs_difference(crs, other)) {
            warnings.push_back(
                "projection keys (3075-3095) disagree with EPSG:" + std::to_string(crs.epsg) +
                ": " + *diff + "; using EPSG:" + std::to_string(crs.epsg));
          }
        }
      }
      return crs;
    }
    if (!user_projection && !(projection_code.value() && *projection_code.value() > 16000 &&
                              *projection_code.value() < 16161)) {
      return key_error(ErrorCode::Unsupported,
                       "ProjectedCSTypeGeoKey (3072) EPSG:" + std::to_string(*code.value()) +
                           " is not a projected CRS in PROJ's EPSG database and the keys define "
                           "no projection");
    }
    warnings.push_back("ProjectedCSTypeGeoKey (3072) EPSG:" + std::to_string(*code.value()) +
                       " is not a projected CRS in PROJ's EPSG database: using the file's "
                       "projection keys");
  }

  // User-defined projected CRS: a geographic base and a projection.
  auto base = geographic_from_keys(keys, warnings);
  if (!base.ok()) return base.error();
  Crs crs = base.value();
  crs.kind = CrsKind::Projected;
  crs.epsg = 0;
  crs.source = "GeoTIFF keys";
  crs.name = citation.empty() ? "user-defined" : citation;
  if (!key_unit) {
    warnings.push_back("ProjLinearUnitsGeoKey (3076) absent: metre assumed");
    key_unit = metre_unit();
  }
  crs.linear_unit = *key_unit;
  const int pc = projection_code.value().value_or(0);
  if (!user_projection && pc > 16000 && pc < 16161 && (pc % 100) >= 1 && (pc % 100) <= 60) {
    // ProjectionGeoKey: 160zz UTM zone zz north, 161zz south.
    const int zone = pc % 100;
    const bool north = pc < 16100;
    crs.projection = utm_projection(zone, north);
    if (citation.empty()) {
      crs.name = crs.datum.name + " / UTM zone " + std::to_string(zone) + (north ? "N" : "S");
    }
  } else if (user_projection) {
    auto p = projection_from_keys(keys, crs.angular_unit, crs.linear_unit, warnings);
    if (!p.ok()) return p.error();
    crs.projection = p.value();
  } else {
    return key_error(
        ErrorCode::InvalidArgument,
        pc != 0 && pc != kUserDefined
            ? "ProjectionGeoKey (3074) " + std::to_string(pc) +
                  " is not supported (only UTM codes 16001-16160)"
            : std::string("user-defined projected CRS without ProjCoordTransGeoKey (3075)"));
  }
  return crs;
}

// The model as a PROJ string (a CRS assembled from keys has no EPSG definition).
std::string proj_definition(const Crs& crs) {
  auto n = [](double v) { return detail::format_number(v); };
  std::string text = crs.kind == CrsKind::Projected
                         ? detail::with_earth(crs.projection->proj_string, crs.datum.ellipsoid)
                         : detail::with_earth("+proj=longlat", crs.datum.ellipsoid);
  if (crs.datum.prime_meridian_deg != 0.0) text += " +pm=" + n(crs.datum.prime_meridian_deg);
  if (crs.datum.to_wgs84 && !crs.datum.to_wgs84->is_null()) {
    const Helmert7& h = *crs.datum.to_wgs84;  // +towgs84 is position vector: negate rotations
    text += " +towgs84=" + n(h.tx_m) + "," + n(h.ty_m) + "," + n(h.tz_m) + "," +
            n(-h.rx_arcsec + 0.0) + "," + n(-h.ry_arcsec + 0.0) + "," + n(-h.rz_arcsec + 0.0) +
            "," + n(h.scale_ppm);
  }
  if (crs.kind == CrsKind::Projected) text += " +to_meter=" + n(crs.linear_unit.metres);
  return text + " +no_defs +type=crs";
}

}  // namespace

Result<Crs> crs_from_geokeys(const std::vector<GeoKeyEntry>& entries) {
  std::vector<std::string> warnings;
  const Keys keys(entries, warnings);
  auto model = keys.code(GTModelType);
  if (!model.ok()) return model.error();
  int type = model.value().value_or(0);
  if (type == 0) {
    if (keys.has(ProjectedCSType) || keys.has(ProjCoordTrans)) {
      type = 1;
    } else if (keys.has(GeographicType) || keys.has(GeogGeodeticDatum) ||
               keys.has(GeogSemiMajorAxis)) {
      type = 2;
    } else {
      return key_error(
          ErrorCode::InvalidArgument,
          "the GeoTIFF keys define no CRS (no GTModelTypeGeoKey, ProjectedCSTypeGeoKey or "
          "GeographicTypeGeoKey)");
    }
    warnings.push_back("GTModelTypeGeoKey (1024) absent: model inferred from the other keys");
  }
  Result<Crs> crs = Error{ErrorCode::InvalidArgument, ""};
  if (type == 1) {
    crs = projected_from_keys(keys, warnings);
  } else if (type == 2) {
    crs = geographic_from_keys(keys, warnings);
  } else if (type == 3) {
    return key_error(ErrorCode::Unsupported,
                     "GTModelTypeGeoKey (1024) 3 (geocentric) is not supported");
  } else {
    return key_error(ErrorCode::InvalidArgument,
                     "GTModelTypeGeoKey (1024) has the invalid value " + std::to_string(type));
  }
  if (!crs.ok()) return crs;
  auto vertical = vertical_from_keys(keys, warnings);
  if (!vertical.ok()) return vertical.error();
  Crs out = std::move(crs).value();
  if (out.epsg == 0 || out.definition.empty()) out.definition = proj_definition(out);
  if (vertical.value()) {
    out.vertical = *vertical.value();
    detail::settle_vertical(out);
  }
  out.warnings.insert(out.warnings.end(), warnings.begin(), warnings.end());
  if (auto status = validate_crs(out); !status.ok()) return status.error();
  // PROJ must compute the projection the keys describe.
  if (auto math = detail::CrsMath::create(out); !math.ok()) {
    return key_error(ErrorCode::InvalidArgument, "GeoTIFF keys: " + math.error().message);
  }
  return out;
}

}  // namespace csgtile::geo
