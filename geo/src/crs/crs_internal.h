#pragma once
// Private helpers shared by the CRS builders: PROJ's database and reader turned into the Crs
// model (proj_model.cpp), units, numbers and names.

#include <optional>
#include <string>
#include <string_view>

#include "csgtile/geo/crs.h"

namespace csgtile::geo::detail {

inline constexpr double kPi = 3.14159265358979323846;
inline constexpr double kDegree = kPi / 180.0;

/// Lower-case letters and digits only: "Lambert_Conformal_Conic_2SP" → "lambertconformalconic2sp".
std::string normalise_name(std::string_view name);

/// Formats a double with the fewest digits that round-trip.
std::string format_number(double v);

/// A linear unit of the given size, snapped to metre / foot / US survey foot when within
/// 1e-12 relative (WKT prints 0.304800609601219 for 1200/3937).
LinearUnit linear_unit_from_size(std::string name, double metres);
AngularUnit angular_unit_from_size(std::string name, double radians);

/// Units, ellipsoids and prime meridians by EPSG code, from PROJ's database; nullopt when the
/// code is none of that kind.
std::optional<LinearUnit> linear_unit_from_epsg(int code);
std::optional<AngularUnit> angular_unit_from_epsg(int code);
std::optional<Ellipsoid> ellipsoid_from_epsg(int code);
/// Greenwich longitude (degrees) of a prime meridian code (8901 Greenwich, 8903 Paris, ...).
std::optional<double> prime_meridian_from_epsg(int code);
/// The EPSG code of a geographic 2D CRS on a datum (6289 → 4289); 0 when there is none.
int geographic_crs_of_datum(int datum_code);

/// A datum by EPSG code, with its relation to WGS 84 (from a geographic CRS on it).
std::optional<GeodeticDatum> datum_from_epsg(int code);
/// A datum of PROJ's EPSG database by name (ESRI "D_" prefix and underscores allowed;
/// letters and digits compared); nullopt when none matches.
std::optional<GeodeticDatum> datum_from_name(std::string_view name);
/// A vertical CRS by EPSG code (name, unit; no geoid model yet); nullopt when none.
std::optional<VerticalCrs> vertical_from_epsg(int code);
/// Looks up the geoid model of `crs.vertical` (an EPSG code) over `crs.definition` (the
/// horizontal CRS) and makes the definition the compound CRS. No-op without a vertical code.
void settle_vertical(Crs& crs);

/// A CRS from PROJ's EPSG database ("EPSG:h" or "EPSG:h+v"), looked up once per process.
/// Errors: Unsupported naming the code.
kernel::Result<Crs> crs_from_proj_database(int code, int vertical_code);
/// A CRS from any text PROJ reads (WKT 1/2, PROJJSON, "EPSG:n", PROJ strings with
/// +type=crs). `what` names the text in messages ("WKT", "PROJJSON", "config"). Texts are
/// remembered (bounded). Errors: InvalidArgument (too long, NUL bytes), Unsupported (PROJ
/// cannot read it, or it is no geographic, projected, geocentric or compound CRS).
kernel::Result<Crs> crs_from_proj_text(std::string_view text, const std::string& what);

/// PROJ's WKT 1 (GDAL dialect) of a definition; empty when PROJ cannot write it.
std::string proj_wkt1(const std::string& definition);
/// PROJ's WKT 1 (GDAL dialect) of a CRS's horizontal part: of EPSG code `epsg` from the
/// database when it is above 0, else of `definition` (its first component when compound).
/// Empty when PROJ cannot write it.
std::string proj_horizontal_wkt1(const std::string& definition, int epsg);

/// `proj_string` with the ellipsoid as PROJ parameters ("+a=… +rf=…", a sphere "+R=…")
/// appended, unless it already names one (+ellps, +a, +R or +datum).
std::string with_earth(const std::string& proj_string, const Ellipsoid& ellipsoid);

/// Helmert given in the position-vector convention (WKT 1 TOWGS84, GeoTIFF 2062, PROJ
/// +towgs84) → coordinate frame.
Helmert7 helmert_from_position_vector(double tx, double ty, double tz, double rx, double ry,
                                      double rz, double ppm);

/// The value of a "+key=value" token of a PROJ string; nullopt when absent or not a number.
std::optional<double> proj_parameter(const std::string& proj_string, std::string_view key);
/// True when the PROJ string has the bare flag or key (e.g. "+south", "+proj=utm").
bool proj_has(const std::string& proj_string, std::string_view token);

}  // namespace csgtile::geo::detail
