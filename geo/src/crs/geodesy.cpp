// Projections (PROJ, with our domain rules) and datum shifts (Helmert in ECEF on GeographicLib's
// geocentric conversions, or PROJ's pipeline) for CrsMath.

#include "crs/geodesy.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <string>

#include <GeographicLib/Geocentric.hpp>
#include <GeographicLib/Math.hpp>

#include "crs/crs_internal.h"
#include "crs/proj_engine.h"

namespace csgtile::geo::detail {
namespace {

using kernel::Error;
using kernel::ErrorCode;
using kernel::Result;

// Every projection is PROJ's (proj_engine.cpp), from a PROJ string on the CRS's ellipsoid in
// metres with longitudes relative to the CRS's prime meridian; the domain rules PROJ does
// not apply are ours, checked around it (DomainChecks).

// The PROJ string of a projection on the CRS's ellipsoid.
std::string proj_string_of(const Crs& crs) {
  return with_earth(crs.projection->proj_string, crs.datum.ellipsoid);
}

// Domain rules around PROJ's projection: transverse Mercator within 90° of its central
// meridian; UTM zones (on any ellipsoid) within their legal window (easting 0-1000 km;
// northing -100..9700 km north, 900..10100 km south), so a tile behaves the same in
// EPSG:32631 and EPSG:25831; polar stereographic never at the opposite pole.
class DomainChecks final : public ProjectionEngine {
 public:
  DomainChecks(std::unique_ptr<ProjectionEngine> inner, const Projection& p)
      : inner_(std::move(inner)) {
    const std::string& text = p.proj_string;
    if (proj_has(text, "+proj=utm")) {
      utm_zone_ = static_cast<int>(proj_parameter(text, "zone").value_or(0.0));
      utm_north_ = !proj_has(text, "+south");
    }
    if (proj_has(text, "+proj=tmerc") || proj_has(text, "+proj=etmerc") || utm_zone_ != 0) {
      central_meridian_ =
          utm_zone_ != 0 ? -183.0 + 6.0 * utm_zone_ : proj_parameter(text, "lon_0").value_or(0.0);
    }
    const double lat0 = proj_parameter(text, "lat_0").value_or(0.0);
    polar_ =
        (proj_has(text, "+proj=stere") || proj_has(text, "+proj=ups")) && std::fabs(lat0) == 90.0;
    polar_north_ = lat0 > 0 || (proj_has(text, "+proj=ups") && !proj_has(text, "+south"));
    if (proj_has(text, "+proj=ups")) polar_ = true;
  }
  void forward(double lat, double lon, double& easting, double& northing) const override {
    if (central_meridian_ &&
        std::fabs(GeographicLib::Math::AngDiff(*central_meridian_, lon)) > 90.0) {
      throw DomainError("longitude " + format_number(lon) +
                        " is more than 90 degrees from the central meridian");
    }
    if (polar_ && ((polar_north_ && lat <= -90.0) || (!polar_north_ && lat >= 90.0))) {
      throw DomainError("the opposite pole cannot be projected");
    }
    inner_->forward(lat, lon, easting, northing);
    check_utm_window(easting, northing);
  }
  void reverse(double easting, double northing, double& lat, double& lon) const override {
    check_utm_window(easting, northing);
    inner_->reverse(easting, northing, lat, lon);
  }
  void reverse_many(double* x, double* y, std::size_t count) const override {
    constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
    if (utm_zone_ != 0) {
      for (std::size_t i = 0; i < count; ++i) {
        if (!in_utm_window(x[i], y[i])) x[i] = y[i] = kNan;
      }
    }
    inner_->reverse_many(x, y, count);
  }

 private:
  bool in_utm_window(double easting, double northing) const {
    return easting >= 0.0 && easting <= 1.0e6 &&
           (utm_north_ ? northing >= -1.0e5 && northing < 9.7e6
                       : northing >= 9.0e5 && northing <= 1.01e7);
  }
  void check_utm_window(double easting, double northing) const {
    if (utm_zone_ == 0 || in_utm_window(easting, northing)) return;
    throw DomainError("easting " + format_number(easting) + ", northing " +
                      format_number(northing) + " out of legal bounds for UTM zone " +
                      std::to_string(utm_zone_) + (utm_north_ ? "N" : "S"));
  }
  std::unique_ptr<ProjectionEngine> inner_;
  std::optional<double> central_meridian_;  // transverse Mercator
  int utm_zone_ = 0;
  bool utm_north_ = true;
  bool polar_ = false;
  bool polar_north_ = true;
};

std::unique_ptr<ProjectionEngine> make_engine(const Crs& crs) {
  auto engine = make_proj_engine(proj_string_of(crs));
  if (!engine.ok()) throw DomainError(engine.error().message);
  return std::make_unique<DomainChecks>(std::move(engine).value(), *crs.projection);
}

void require_finite(double a, double b, const char* what) {
  if (!std::isfinite(a) || !std::isfinite(b)) throw DomainError(std::string("non-finite ") + what);
}

}  // namespace

Result<std::shared_ptr<const CrsMath>> CrsMath::create(const Crs& crs) {
  if (auto status = validate_crs(crs); !status.ok()) return status.error();
  auto math = std::shared_ptr<CrsMath>(new CrsMath(crs));
  math->z_to_metres_ = crs.z_unit_metres();
  math->prime_meridian_deg_ = crs.datum.prime_meridian_deg;
  if (crs.vertical && !crs.vertical->to_ellipsoidal_pipeline.empty()) {
    auto geoid = make_geodetic_transform(crs.vertical->to_ellipsoidal_pipeline);
    if (!geoid.ok()) return geoid.error();
    math->geoid_ = std::move(geoid).value();
  }
  if (crs.kind == CrsKind::Geographic) {
    math->xy_to_degrees_ = crs.angular_unit.radians / kDegree;
    if (crs.angular_unit.epsg == 9102) math->xy_to_degrees_ = 1.0;  // exact for degrees
  } else if (crs.kind == CrsKind::Geocentric) {
    math->xy_to_metres_ = crs.linear_unit.metres;
    math->z_to_metres_ = crs.linear_unit.metres;
    try {
      math->earth_ = std::make_shared<const GeographicLib::Geocentric>(
          crs.datum.ellipsoid.semi_major_m, crs.datum.ellipsoid.flattening());
    } catch (const std::exception& e) {
      return Error{ErrorCode::InvalidArgument,
                   "ellipsoid '" + crs.datum.ellipsoid.name + "' refused: " + e.what()};
    }
  } else {
    math->xy_to_metres_ = crs.linear_unit.metres;
    try {
      math->engine_ = make_engine(crs);
    } catch (const std::exception& e) {
      return Error{ErrorCode::InvalidArgument,
                   crs.projection->method_name + " parameters refused: " + e.what()};
    }
  }
  return std::shared_ptr<const CrsMath>(std::move(math));
}

void ProjectionEngine::reverse_many(double* x, double* y, std::size_t count) const {
  for (std::size_t i = 0; i < count; ++i) {
    double lat = 0.0, lon = 0.0;
    try {
      reverse(x[i], y[i], lat, lon);
    } catch (const std::exception&) {
      lat = lon = std::numeric_limits<double>::quiet_NaN();
    }
    x[i] = lat;
    y[i] = lon;
  }
}

GeodeticPoint CrsMath::to_geodetic(const kernel::Vec3& xyz) const {
  GeodeticPoint g;
  if (earth_) {
    require_finite(xyz.x(), xyz.y(), "coordinates");
    if (!std::isfinite(xyz.z())) throw DomainError("non-finite coordinates");
    earth_->Reverse(xyz.x() * xy_to_metres_, xyz.y() * xy_to_metres_, xyz.z() * z_to_metres_,
                    g.latitude_deg, g.longitude_deg, g.height_m);
    require_finite(g.latitude_deg, g.longitude_deg, "geodetic result");
    if (prime_meridian_deg_ != 0.0)
      g.longitude_deg = GeographicLib::Math::AngNormalize(g.longitude_deg + prime_meridian_deg_);
    return g;
  }
  g.height_m = xyz.z() * z_to_metres_;
  if (!engine_) {
    g.longitude_deg = xyz.x() * xy_to_degrees_;
    g.latitude_deg = xyz.y() * xy_to_degrees_;
    require_finite(g.latitude_deg, g.longitude_deg, "coordinates");
    if (std::fabs(g.latitude_deg) > 90.0)
      throw DomainError("latitude " + format_number(g.latitude_deg) + " beyond ±90");
  } else {
    require_finite(xyz.x(), xyz.y(), "coordinates");
    engine_->reverse(xyz.x() * xy_to_metres_, xyz.y() * xy_to_metres_, g.latitude_deg,
                     g.longitude_deg);
    require_finite(g.latitude_deg, g.longitude_deg, "geodetic result");
  }
  if (prime_meridian_deg_ != 0.0)
    g.longitude_deg = GeographicLib::Math::AngNormalize(g.longitude_deg + prime_meridian_deg_);
  to_ellipsoidal(g);
  return g;
}

void CrsMath::to_ellipsoidal(GeodeticPoint& g) const {
  if (!geoid_) return;
  double lat = g.latitude_deg, lon = g.longitude_deg;
  geoid_->forward(lat, lon, g.height_m);  // the model moves heights only
}

void CrsMath::to_gravity_related(GeodeticPoint& g) const {
  if (!geoid_) return;
  double lat = g.latitude_deg, lon = g.longitude_deg;
  geoid_->inverse(lat, lon, g.height_m);
}

void CrsMath::to_geodetic_many(std::span<const kernel::Vec3> in,
                               std::span<GeodeticPoint> out) const {
  constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
  if (!engine_) {
    for (std::size_t i = 0; i < in.size(); ++i) {
      try {
        out[i] = to_geodetic(in[i]);
      } catch (const std::exception&) {
        out[i] = GeodeticPoint{kNan, kNan, kNan};
      }
    }
    return;
  }
  // Projected: the projection in batches (PROJ transforms a batch per call), units and the
  // prime meridian around it.
  constexpr std::size_t kBatch = 1024;
  double x[kBatch];
  double y[kBatch];
  for (std::size_t start = 0; start < in.size(); start += kBatch) {
    const std::size_t n = std::min(kBatch, in.size() - start);
    for (std::size_t i = 0; i < n; ++i) {
      const kernel::Vec3& p = in[start + i];
      const bool ok = std::isfinite(p.x()) && std::isfinite(p.y());
      x[i] = ok ? p.x() * xy_to_metres_ : kNan;
      y[i] = ok ? p.y() * xy_to_metres_ : kNan;
    }
    engine_->reverse_many(x, y, n);
    for (std::size_t i = 0; i < n; ++i) {
      GeodeticPoint& g = out[start + i];
      g.latitude_deg = x[i];
      g.longitude_deg = y[i];
      g.height_m = in[start + i].z() * z_to_metres_;
      if (!std::isfinite(g.latitude_deg) || !std::isfinite(g.longitude_deg)) {
        g = GeodeticPoint{kNan, kNan, kNan};
      } else {
        if (prime_meridian_deg_ != 0.0) {
          g.longitude_deg =
              GeographicLib::Math::AngNormalize(g.longitude_deg + prime_meridian_deg_);
        }
        try {
          to_ellipsoidal(g);
        } catch (const std::exception&) {
          g = GeodeticPoint{kNan, kNan, kNan};
        }
      }
    }
  }
}

kernel::Vec3 CrsMath::from_geodetic(const GeodeticPoint& given) const {
  require_finite(given.latitude_deg, given.longitude_deg, "geodetic coordinates");
  GeodeticPoint point = given;
  if (!earth_) to_gravity_related(point);
  if (std::fabs(point.latitude_deg) > 90.0)
    throw DomainError("latitude " + format_number(point.latitude_deg) + " beyond ±90");
  double lon = point.longitude_deg;
  if (prime_meridian_deg_ != 0.0)
    lon = GeographicLib::Math::AngNormalize(lon - prime_meridian_deg_);
  if (earth_) {
    kernel::Vec3 x;
    earth_->Forward(point.latitude_deg, lon, point.height_m, x.x(), x.y(), x.z());
    return x / xy_to_metres_;
  }
  const double z = point.height_m / z_to_metres_;
  if (!engine_) return kernel::Vec3(lon / xy_to_degrees_, point.latitude_deg / xy_to_degrees_, z);
  double e = 0.0, n = 0.0;
  engine_->forward(point.latitude_deg, lon, e, n);
  require_finite(e, n, "projected result");
  return kernel::Vec3(e / xy_to_metres_, n / xy_to_metres_, z);
}

Result<DatumShift> DatumShift::create(const GeodeticDatum& datum) {
  if (!datum.to_wgs84_pipeline.empty()) {
    auto pipeline = make_geodetic_transform(datum.to_wgs84_pipeline);
    if (!pipeline.ok()) return pipeline.error();
    DatumShift shift;
    shift.identity_ = false;
    shift.pipeline_ = std::move(pipeline).value();
    return shift;
  }
  if (!datum.to_wgs84) {
    return Error{ErrorCode::Unsupported,
                 "datum '" + datum.name + "' has no known transformation to WGS 84 (" +
                     datum.to_wgs84_source + "); supply TOWGS84 in the CRS"};
  }
  DatumShift shift;
  try {
    shift.earth_ = std::make_shared<const GeographicLib::Geocentric>(datum.ellipsoid.semi_major_m,
                                                                     datum.ellipsoid.flattening());
  } catch (const std::exception& e) {
    return Error{ErrorCode::InvalidArgument,
                 "ellipsoid '" + datum.ellipsoid.name + "' refused: " + e.what()};
  }
  const Helmert7& h = *datum.to_wgs84;
  shift.identity_ = h.is_null();
  if (!shift.identity_) {
    const double arcsec = kPi / 648000.0;
    const double rx = h.rx_arcsec * arcsec, ry = h.ry_arcsec * arcsec, rz = h.rz_arcsec * arcsec;
    Eigen::Matrix3d r;
    // Coordinate-frame rotation, small-angle form (EPSG GN 7-2 §4.3.3, method 1032/9607).
    r << 1.0, rz, -ry,  //
        -rz, 1.0, rx,   //
        ry, -rx, 1.0;
    shift.matrix_ = (1.0 + h.scale_ppm * 1e-6) * r;
    shift.inverse_ = shift.matrix_.inverse();
    shift.translation_ = kernel::Vec3(h.tx_m, h.ty_m, h.tz_m);
  }
  return shift;
}

kernel::Vec3 DatumShift::to_wgs84_ecef(const GeodeticPoint& p) const {
  kernel::Vec3 x;
  if (pipeline_) {
    GeodeticPoint w = p;
    pipeline_->forward(w.latitude_deg, w.longitude_deg, w.height_m);
    GeographicLib::Geocentric::WGS84().Forward(w.latitude_deg, w.longitude_deg, w.height_m, x.x(),
                                               x.y(), x.z());
    return x;
  }
  const GeographicLib::Geocentric& earth = identity_ ? GeographicLib::Geocentric::WGS84() : *earth_;
  earth.Forward(p.latitude_deg, p.longitude_deg, p.height_m, x.x(), x.y(), x.z());
  return identity_ ? x : apply(x);
}

GeodeticPoint DatumShift::from_wgs84_ecef(const kernel::Vec3& ecef) const {
  GeodeticPoint p;
  if (pipeline_) {
    GeographicLib::Geocentric::WGS84().Reverse(ecef.x(), ecef.y(), ecef.z(), p.latitude_deg,
                                               p.longitude_deg, p.height_m);
    pipeline_->inverse(p.latitude_deg, p.longitude_deg, p.height_m);
    return p;
  }
  if (identity_) {
    GeographicLib::Geocentric::WGS84().Reverse(ecef.x(), ecef.y(), ecef.z(), p.latitude_deg,
                                               p.longitude_deg, p.height_m);
  } else {
    const kernel::Vec3 x = apply_inverse(ecef);
    earth_->Reverse(x.x(), x.y(), x.z(), p.latitude_deg, p.longitude_deg, p.height_m);
  }
  return p;
}

Eigen::Matrix3d enu_rotation(double lat_deg, double lon_deg) {
  double sphi = 0.0, cphi = 0.0, slam = 0.0, clam = 0.0;
  GeographicLib::Math::sincosd(lat_deg, sphi, cphi);
  GeographicLib::Math::sincosd(lon_deg, slam, clam);
  Eigen::Matrix3d r;
  r.col(0) = kernel::Vec3(-slam, clam, 0.0);                  // east
  r.col(1) = kernel::Vec3(-sphi * clam, -sphi * slam, cphi);  // north
  r.col(2) = kernel::Vec3(cphi * clam, cphi * slam, sphi);    // up
  return r;
}

}  // namespace csgtile::geo::detail
