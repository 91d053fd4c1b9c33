#pragma once
// Private helpers shared by the CRS builders: the EPSG tables (ellipsoids, datums, units,
// vertical CRSs) and name normalisation.

#include <optional>
#include <string>
#include <string_view>

#include "csgtile/geo/crs.h"

namespace csgtile::geo::detail {

inline constexpr double kPi = 3.14159265358979323846;
inline constexpr double kDegree = kPi / 180.0;
inline constexpr double kArcSecondsPerMicroradian = 648000.0 / kPi / 1e6;

/// Lower-case letters and digits only: "Lambert_Conformal_Conic_2SP" → "lambertconformalconic2sp".
std::string normalise_name(std::string_view name);

std::optional<Ellipsoid> ellipsoid_from_epsg(int code);
/// Datum by EPSG datum code (6326, 6258, 6289, ...), with its relation to WGS 84.
std::optional<GeodeticDatum> datum_from_epsg(int code);
/// Datum recognised by a (normalised) name, for WKT without AUTHORITY and GeoTIFF citations:
/// WGS 84, ETRS89, NAD83 (+HARN, 2011, CSRS), Amersfoort, OSGB36, NZGD2000, RGF93, IRENET95.
std::optional<GeodeticDatum> datum_from_name(std::string_view name);
std::optional<LinearUnit> linear_unit_from_epsg(int code);
/// Known unit by name ("US survey foot", "Foot_US", "ftUS", "foot", "metre", "meter", ...).
std::optional<LinearUnit> linear_unit_from_name(std::string_view name);
std::optional<AngularUnit> angular_unit_from_epsg(int code);
std::optional<AngularUnit> angular_unit_from_name(std::string_view name);
/// A linear unit of the given size, snapped to metre / foot / US survey foot when within
/// 1e-12 relative (WKT prints 0.304800609601219 for 1200/3937).
LinearUnit linear_unit_from_size(std::string name, double metres);
AngularUnit angular_unit_from_size(std::string name, double radians);
/// Known vertical CRS name by EPSG code (empty when unknown) and its unit.
std::optional<VerticalCrs> vertical_from_epsg(int code);

/// A CRS from PROJ's EPSG database (proj_database.cpp), for codes outside the table: its
/// WKT 1 read by crs_from_wkt, the datum's Helmert to WGS 84 as PROJ ranks it. Errors:
/// Unsupported naming the code (not in the database, geocentric, a method not computed).
kernel::Result<Crs> crs_from_proj_database(int code);
/// A CRS from any text PROJ reads (WKT 1/2, PROJJSON, "EPSG:n", PROJ strings with
/// +type=crs): our WKT reader on PROJ's WKT 1 where it models the CRS, else a projection
/// computed by PROJ (ProjectionMethod::ComputedByProj) or a geocentric CRS. `what` names the
/// text in messages ("WKT", "PROJJSON", "EPSG:5514"). Errors: Unsupported (PROJ cannot read
/// it, or it is no geographic, projected, geocentric or compound CRS).
kernel::Result<Crs> crs_from_proj_text(std::string_view text, const std::string& what);
/// WKT 1 of a projected CRS computed by PROJ whose projection came as a bare PROJ string
/// (GeoTIFF keys): PROJ writes it from the string, the ellipsoid, the Helmert and the unit.
std::string proj_projected_wkt1(const Crs& crs);
/// `proj_string` with the ellipsoid as PROJ parameters ("+a=… +rf=…", a sphere "+R=…")
/// appended, unless it already names one (+ellps, +a, +R or +datum).
std::string with_earth(const std::string& proj_string, const Ellipsoid& ellipsoid);
/// Our own WKT reader alone (crs_from_wkt falls back to PROJ for what it refuses).
kernel::Result<Crs> crs_from_wkt_own(std::string_view wkt);
/// A vertical CRS's name and unit from PROJ's database; nullopt when it is none.
std::optional<VerticalCrs> vertical_from_proj_database(int code);

/// Geographic CRS of the table (4326, 4258, ...).
std::optional<Crs> geographic_from_epsg(int code);

/// Helmert given in the position-vector convention (WKT 1 TOWGS84, GeoTIFF 2062, PROJ
/// +towgs84) → coordinate frame.
Helmert7 helmert_from_position_vector(double tx, double ty, double tz, double rx, double ry,
                                      double rz, double ppm);

/// True when a projection's parameters are exactly a UTM zone (zone 1..60, north flag set)
/// or UPS (zone 0).
bool is_utm(const Projection& p, int* zone, bool* north);
bool is_ups(const Projection& p, bool* north);

/// Is this datum's ellipsoid WGS 84 exactly?
bool is_wgs84_ellipsoid(const Ellipsoid& e);

/// Formats a double with enough digits to round-trip.
std::string format_number(double v);

}  // namespace csgtile::geo::detail
