#pragma once
/// \file
/// Coordinate reference systems as plain descriptions: what a LIDAR tile's coordinates mean.
///
/// Every CRS is read by PROJ (Debian libproj, its EPSG database in proj-data): EPSG codes,
/// OGC WKT 1 (GDAL and ESRI dialects) and WKT 2, PROJJSON, PROJ strings, and GeoTIFF keys
/// (LAS GeoKeyDirectory VLRs), which are mapped to EPSG codes or, when user-defined, to a
/// PROJ string. The Crs below is what PROJ says about the CRS, in the terms georeference.h
/// computes with; nothing here computes coordinates.
///
/// Conventions (all builders normalise to them):
///  - x is easting / longitude, y is northing / latitude, whatever the authority's axis order
///    (LAS and most GIS files store easting first; so does this model).
///  - `linear_unit` / `angular_unit` say what the coordinates themselves are in; the
///    projection is a PROJ string in metres.
///  - The datum's relation to WGS 84 is the transformation PROJ ranks first among those whose
///    grids are installed (or the definition's own TOWGS84): a 7-parameter Helmert kept in the
///    coordinate-frame rotation convention (EPSG method 1032/9607), or PROJ's pipeline.
///
/// Errors (kernel::Result): InvalidArgument for malformed, incomplete or out-of-range
/// definitions (WKT syntax, a missing projection parameter, a GeoTIFF directory without a CRS);
/// Unsupported for definitions PROJ cannot read or that are no usable CRS (an unknown EPSG
/// code, an engineering CRS). Messages name the key, the code or PROJ's reason.

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "csgtile/kernel/result.h"

namespace csgtile::geo {

/// A reference ellipsoid. inverse_flattening == 0 means a sphere.
struct Ellipsoid {
  std::string name = "WGS 84";
  int epsg = 7030;
  double semi_major_m = 6378137.0;
  double inverse_flattening = 298.257223563;

  double flattening() const { return inverse_flattening == 0.0 ? 0.0 : 1.0 / inverse_flattening; }
};

/// Seven-parameter Helmert transformation from a datum to WGS 84, coordinate-frame rotation
/// convention (EPSG 1032/9607, small-angle form): X_wgs84 = (1 + s) · R · X + T with
/// R = [[1, rz, -ry], [-rz, 1, rx], [ry, -rx, 1]]. WKT 1 TOWGS84 and GeoTIFF key 2062 use the
/// position-vector convention; their builders negate the rotations.
struct Helmert7 {
  double tx_m = 0.0, ty_m = 0.0, tz_m = 0.0;
  double rx_arcsec = 0.0, ry_arcsec = 0.0, rz_arcsec = 0.0;
  double scale_ppm = 0.0;

  /// True when every parameter is zero (a null transformation).
  bool is_null() const;
};

/// A geodetic datum: ellipsoid, prime meridian and its relation to WGS 84.
struct GeodeticDatum {
  std::string name = "WGS 84";
  int epsg = 6326;
  Ellipsoid ellipsoid;
  double prime_meridian_deg = 0.0;  ///< Greenwich longitude of the prime meridian
  /// The transformation to WGS 84; nullopt when unknown (such a CRS can be read and projected
  /// but not placed on the globe). All zeros for datums that EPSG relates to WGS 84 by a null
  /// transformation (ETRS89, NAD83 and their realisations: metre-level agreement).
  std::optional<Helmert7> to_wgs84 = Helmert7{};
  /// When PROJ's best transformation to WGS 84 is not a Helmert (a grid shift whose grid is
  /// installed, e.g. BETA2007 for DHDN): its PROJ pipeline from longitude, latitude (degrees)
  /// and height on this datum to WGS 84, used instead of to_wgs84 (then nullopt).
  std::string to_wgs84_pipeline;
  /// What the relation is, e.g. "EPSG:9281 Amersfoort to ETRS89 (8)" or, from PROJ, the
  /// operation's name, code and accuracy: written into every run's manifest.
  std::string to_wgs84_source = "identity";
};

/// A unit of length. US survey foot: 1200/3937 m; international foot: 0.3048 m.
struct LinearUnit {
  std::string name = "metre";
  double metres = 1.0;  ///< size of one unit in metres
  int epsg = 9001;      ///< 0 when not an EPSG unit
};

/// A unit of angle.
struct AngularUnit {
  std::string name = "degree";
  double radians = 0.017453292519943295;  ///< size of one unit in radians
  int epsg = 9102;
};

LinearUnit metre_unit();
LinearUnit international_foot_unit();  ///< EPSG:9002, 0.3048 m
LinearUnit us_survey_foot_unit();      ///< EPSG:9003, 1200/3937 m
AngularUnit degree_unit();

/// The projection of a projected CRS, computed by PROJ: every method PROJ knows (transverse
/// Mercator and UTM, Lambert conic, oblique and polar stereographic, Krovak, Hotine / Swiss
/// oblique Mercator, Mercator, Lambert azimuthal equal area, Albers, ...).
struct Projection {
  std::string method_name;  ///< EPSG name of the method, e.g. "Oblique Stereographic"
  /// The projection as a PROJ string on the CRS's ellipsoid, in metres, longitudes relative
  /// to the CRS's prime meridian (e.g. "+proj=sterea +lat_0=52.15616055555555 ... +a=… +rf=…").
  std::string proj_string;
};

/// A vertical CRS (gravity-related heights such as NAP or NAVD88). Its unit scales z; its
/// relation to ellipsoidal heights is the transformation PROJ ranks first among those whose
/// grids are installed (a geoid model), applied by georeference.h. Without one, heights are
/// taken as ellipsoidal and the CRS carries a warning saying so.
struct VerticalCrs {
  int epsg = 0;
  std::string name;
  LinearUnit unit;
  /// PROJ pipeline from (longitude, latitude in degrees, height in metres on this vertical
  /// CRS) on the horizontal CRS's datum to its ellipsoidal height; empty when none is
  /// installed.
  std::string to_ellipsoidal_pipeline = {};
  /// What that relation is (PROJ's operation, its grid and accuracy) or why there is none:
  /// written into every run's manifest.
  std::string to_ellipsoidal_source = {};
};

/// Geographic: x longitude, y latitude. Projected: x easting, y northing. Geocentric: x, y, z
/// Earth-centred Earth-fixed on the datum's ellipsoid, in the linear unit (e.g. EPSG:4978).
enum class CrsKind { Geographic, Projected, Geocentric };

/// A horizontal CRS (geographic, projected or geocentric) with an optional vertical CRS.
struct Crs {
  CrsKind kind = CrsKind::Geographic;
  std::string name = "WGS 84";
  int epsg = 4326;  ///< 0 for user-defined
  GeodeticDatum datum;
  AngularUnit angular_unit;              ///< unit of x, y of a geographic CRS
  LinearUnit linear_unit;                ///< unit of x, y (z) of a projected (geocentric) CRS
  std::optional<Projection> projection;  ///< set exactly when kind == Projected
  std::optional<VerticalCrs> vertical;
  /// What a builder had to assume or ignore (e.g. "user-defined datum assumed to be WGS 84").
  std::vector<std::string> warnings;
  std::string source;  ///< "EPSG:2992", "GeoTIFF keys", "WKT", "config"
  /// The whole CRS as PROJ reads it (OGC WKT 2:2019 as PROJ writes it, or a PROJ string for
  /// CRSs assembled from GeoTIFF keys): what crs_to_wkt1 and the outputs write.
  std::string definition = {};

  bool is_projected() const { return kind == CrsKind::Projected; }
  /// Metres per unit of z: the vertical CRS's unit, else the horizontal linear unit of a
  /// projected CRS (the LAS convention), else 1 (ellipsoidal height in metres).
  double z_unit_metres() const;
};

/// One GeoTIFF key as a LAS reader finds it: SHORT values and DOUBLE params both as numbers;
/// ASCII params in text (a trailing '|' or NUL is ignored).
struct GeoKeyEntry {
  std::uint16_t id = 0;
  std::vector<double> numbers;
  std::string text;
};

/// A CRS from PROJ's EPSG database: any geographic, projected, geocentric or compound code.
/// `vertical_epsg` (optional) adds a vertical CRS (as "EPSG:h+v"). Looked up once per
/// process. Errors: Unsupported naming the code (not in the database, or not usable).
kernel::Result<Crs> crs_from_epsg(int code, int vertical_epsg = 0);

/// A CRS from GeoTIFF keys (GeoTIFF 1.0/1.1 ids) mapped for PROJ: model type 1024; EPSG codes
/// 2048 (geographic), 3072 (projected), 3074 (UTM projection codes 16001–16160), 4096
/// (vertical); user-defined geographic CRSs (2050 datum, 2051/2061 prime meridian, 2054/2055
/// angular unit, 2056–2059 ellipsoid, 2062 TOWGS84) and projections (3075 method: 1 TM, 7
/// Mercator, 8 LCC 2SP, 9 LCC 1SP, 10 LAEA, 11 Albers, 12 azimuthal equidistant, 14
/// stereographic, 15 polar stereographic, 16 oblique stereographic, 17 equirectangular, 18
/// Cassini, 22 polyconic, 24 sinusoidal; 3078–3095 parameters in the angular unit and in the
/// linear unit 3076/3077) become a PROJ string; vertical unit 4099. A linear-unit key that
/// differs from an EPSG code's unit overrides it (coordinates are in the key's unit) with a
/// warning. Unknown and zero key ids are ignored with a warning.
/// Errors: InvalidArgument (no CRS, missing parameters), Unsupported (method, code, model).
kernel::Result<Crs> crs_from_geokeys(const std::vector<GeoKeyEntry>& keys);

/// A CRS from OGC WKT 1 (incl. ESRI and GDAL dialects) or WKT 2 (2015/2019) text, read by PROJ
/// (not strictly: what GDAL writes is accepted). Length is bounded (64 KiB) and NUL bytes are
/// refused. Errors: Unsupported naming PROJ's reason.
kernel::Result<Crs> crs_from_wkt(std::string_view wkt);

/// A CRS from configuration text: "EPSG:28992", "EPSG:28992+5709", "28992", WKT, PROJJSON or a
/// PROJ string with +type=crs.
kernel::Result<Crs> crs_from_config(std::string_view text);

/// Checks what georeference.h relies on: a > 0, 0 <= f < 1, units > 0, a projected CRS has its
/// PROJ string, finiteness.
kernel::Status validate_crs(const Crs& crs);

/// nullopt when the two CRSs compute the same coordinates: ellipsoid, datum shift, prime
/// meridian and units within 1e-9 relative (1e-6 of a Helmert parameter), and projections that
/// give the same coordinates within 0.5 mm at points around the projection's origin (EPSG
/// rounds feet-based false origins to 0.001 ft); otherwise a message naming the first
/// difference and both values. Names and EPSG codes are not compared.
std::optional<std::string> crs_difference(const Crs& a, const Crs& b);

/// The readings of one file (and the config) to reconcile. Each is either absent, a CRS, or
/// the error its builder returned.
struct CrsCandidates {
  std::optional<kernel::Result<Crs>> wkt;
  std::optional<kernel::Result<Crs>> geokeys;
  std::optional<kernel::Result<Crs>> config;
  /// When true the config CRS wins over the file's; otherwise it is used only when the file
  /// has no readable CRS.
  bool config_overrides_file = false;
};

/// Picks one CRS: config (if it overrides), else WKT, else GeoTIFF keys, else config. Every
/// other present reading that disagrees (crs_difference) or failed becomes a warning on the
/// returned CRS naming both sources. Errors: the chosen source's error when every present
/// reading failed; InvalidArgument "no CRS" when none is present.
kernel::Result<Crs> reconcile_crs(const CrsCandidates& candidates);

/// One line for logs and `csgtile info`, e.g.
/// "EPSG:2992 NAD83 / Oregon GIC Lambert (ft): Lambert Conic Conformal (2SP), foot".
std::string describe_crs(const Crs& crs);

/// OGC WKT 1 (GDAL dialect, as PROJ writes it from the definition: TOWGS84 and AUTHORITY where
/// known, COMPD_CS when a vertical CRS is set), e.g. for writing LAS 1.4 files.
/// crs_from_wkt(crs_to_wkt1(c)) is equivalent to c.
std::string crs_to_wkt1(const Crs& crs);

/// OGC WKT 1 (GDAL dialect) of the horizontal part alone (never COMPD_CS): PROJ's database
/// entry when the CRS has an EPSG code (AUTHORITY and TOWGS84 as EPSG gives them), else its
/// definition's horizontal component. What a GeoPackage's spatial reference row for the
/// horizontal code holds. Empty when PROJ cannot write it.
std::string crs_to_horizontal_wkt1(const Crs& crs);

}  // namespace csgtile::geo
