#pragma once
// Private computing side of a Crs: its projection (PROJ, proj_engine.h, with our domain rules)
// with unit handling, its geoid model (PROJ's pipeline), and its datum shift to WGS 84 (a
// Helmert in ECEF, or PROJ's pipeline).
// GeographicLib stays for what it is best at: geocentric conversions and ENU frames.
//
// Calls here throw (DomainError, GeographicLib::GeographicErr); the public wrappers in
// georeference.cpp catch and turn them into kernel errors or NaNs.

#include <cstddef>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>

#include <Eigen/Core>

#include "csgtile/geo/crs.h"
#include "csgtile/geo/georeference.h"
#include "csgtile/kernel/result.h"

namespace GeographicLib {
class Geocentric;
}

namespace csgtile::geo::detail {
class GeodeticTransform;
}

namespace csgtile::geo::detail {

/// A point outside a projection's domain (our checks; GeographicLib throws its own).
class DomainError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A projection in metres and degrees (longitudes relative to the CRS's prime meridian).
class ProjectionEngine {
 public:
  virtual ~ProjectionEngine() = default;
  virtual void forward(double lat, double lon, double& easting, double& northing) const = 0;
  virtual void reverse(double easting, double northing, double& lat, double& lon) const = 0;
  /// Bulk reverse in place: on entry x[i], y[i] are easting and northing (metres), on exit
  /// latitude and longitude (degrees). A point outside the domain gets NaNs; never throws.
  /// The default calls reverse() point by point; PROJ's engine transforms the batch at once.
  virtual void reverse_many(double* x, double* y, std::size_t count) const;
};

/// A Crs made computable. Immutable; const calls are thread-safe.
class CrsMath {
 public:
  /// Errors: validate_crs's; InvalidArgument when GeographicLib refuses the parameters.
  static kernel::Result<std::shared_ptr<const CrsMath>> create(const Crs& crs);

  const Crs& crs() const { return crs_; }
  /// CRS coordinates → geodetic on the CRS's datum (Greenwich longitudes; heights of a vertical
  /// CRS made ellipsoidal by its geoid model when one is installed). Throws.
  GeodeticPoint to_geodetic(const kernel::Vec3& xyz) const;
  /// Geodetic on the CRS's datum → CRS coordinates. Throws.
  kernel::Vec3 from_geodetic(const GeodeticPoint& point) const;
  /// Bulk to_geodetic; a point it cannot convert gets NaNs (to_geodetic on it says why).
  /// `out` has the size of `in`. Never throws.
  void to_geodetic_many(std::span<const kernel::Vec3> in, std::span<GeodeticPoint> out) const;

 private:
  explicit CrsMath(Crs crs) : crs_(std::move(crs)) {}
  // Heights of the vertical CRS ↔ ellipsoidal through the geoid model (no-op without one).
  void to_ellipsoidal(GeodeticPoint& g) const;
  void to_gravity_related(GeodeticPoint& g) const;
  Crs crs_;
  std::unique_ptr<ProjectionEngine> engine_;  // null for geographic and geocentric CRSs
  std::shared_ptr<const GeographicLib::Geocentric> earth_;  // geocentric CRSs: the ellipsoid
  std::shared_ptr<const GeodeticTransform> geoid_;          // vertical CRS → ellipsoidal heights
  double xy_to_metres_ = 1.0;                               // projected
  double xy_to_degrees_ = 1.0;                              // geographic
  double z_to_metres_ = 1.0;
  double prime_meridian_deg_ = 0.0;
};

/// The datum → WGS 84 relation as ECEF maps. Identity for null transformations (geodetic
/// coordinates are carried over unchanged, as EPSG's null transformations do); otherwise the
/// small-angle Helmert of crs.h and its exact matrix inverse.
class DatumShift {
 public:
  /// Errors: Unsupported when the datum's relation to WGS 84 is unknown.
  static kernel::Result<DatumShift> create(const GeodeticDatum& datum);

  bool is_identity() const { return identity_; }
  /// Geodetic on the datum → WGS 84 ECEF.
  kernel::Vec3 to_wgs84_ecef(const GeodeticPoint& point) const;
  /// WGS 84 ECEF → geodetic on the datum.
  GeodeticPoint from_wgs84_ecef(const kernel::Vec3& ecef) const;
  /// Datum ECEF ↔ WGS 84 ECEF (the Helmert itself).
  kernel::Vec3 apply(const kernel::Vec3& datum_ecef) const {
    return matrix_ * datum_ecef + translation_;
  }
  kernel::Vec3 apply_inverse(const kernel::Vec3& wgs84_ecef) const {
    return inverse_ * (wgs84_ecef - translation_);
  }

 private:
  bool identity_ = true;
  std::shared_ptr<const GeodeticTransform> pipeline_;       // PROJ's, instead of the Helmert
  std::shared_ptr<const GeographicLib::Geocentric> earth_;  // the datum's ellipsoid
  Eigen::Matrix3d matrix_ = Eigen::Matrix3d::Identity();    // (1 + s)·R
  Eigen::Matrix3d inverse_ = Eigen::Matrix3d::Identity();
  kernel::Vec3 translation_ = kernel::Vec3::Zero();
};

/// ENU → ECEF rotation at a geodetic point on an ellipsoid (columns east, north, up).
Eigen::Matrix3d enu_rotation(double lat_deg, double lon_deg);

}  // namespace csgtile::geo::detail
