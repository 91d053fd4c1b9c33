#pragma once
/// \file
/// Georeferencing: a CRS's coordinates ↔ geodetic ↔ ECEF ↔ a tile-local east-north-up frame,
/// and terrestrial scanner poses into that frame.
///
/// Exact path. A point in a projected (or geographic) CRS is taken per point through
/// projected → geodetic on the CRS's datum → ECEF on its ellipsoid → Helmert to WGS 84 (when
/// the datum has one) → the tile's ENU frame. The ENU frame of a small tile is close to a
/// similarity of projected coordinates but not equal to one (grid scale and convergence
/// vary across a tile and the Earth curves away from the tangent plane: ~8 cm of drop 1 km
/// from the origin), so no Location stands for "projected → local". A Location does stand,
/// exactly, for the frame's placement on the globe: TileFrame::local_to_ecef is a rotation and
/// a translation from ENU to WGS 84 ECEF. Models keep small local coordinates plus that
/// Location and the geodetic origin.
///
/// Datums. "WGS 84" here means the hub every datum is related to, by the transformation PROJ
/// ranks first among those whose grids are installed (crs.h): a Helmert applied in ECEF, the
/// identity for PROJ's null transformations (ETRS89, NAD83: geodetic coordinates carried over
/// unchanged; metre-level), or PROJ's own pipeline (a grid shift such as BETA2007 for DHDN).
///
/// Heights. z is scaled by the CRS's z unit; heights of a vertical CRS are made ellipsoidal by
/// the geoid model PROJ ranks first whose grid is installed (VerticalCrs::
/// to_ellipsoidal_pipeline, e.g. EGM96 by egm96_15.gtx). Without one they enter as if
/// ellipsoidal, unless a constant undulation is supplied in GeoreferenceOptions. Ignoring an
/// undulation N shifts the frame by N vertically and scales horizontal distances by N / R
/// (7 ppm for N = 43 m).
///
/// Projections are PROJ's (every method it computes, in batches for bulk work), with our own
/// domain rules around them (UTM legal windows, transverse Mercator within 90° of its central
/// meridian, no opposite pole); GeographicLib gives the geocentric conversions and ENU frames.
///
/// Errors: kernel::ErrorCode::InvalidArgument for points outside a projection's domain
/// (PROJ's reason, or ours, kept in the message) and bad options; Unsupported for a datum with no
/// known relation to WGS 84. Thread-safety: every type here is an immutable value; all const calls
/// may run concurrently.

#include <memory>
#include <optional>
#include <span>
#include <string>

#include <Eigen/Core>

#include "csgtile/geo/crs.h"
#include "csgtile/kernel/location.h"
#include "csgtile/kernel/result.h"

namespace csgtile::geo {

/// Geodetic coordinates: latitude and longitude in degrees (Greenwich), ellipsoidal height in
/// metres. Which datum is said by the function that returns one.
struct GeodeticPoint {
  double latitude_deg = 0.0;
  double longitude_deg = 0.0;
  double height_m = 0.0;
};

/// CRS coordinates (x, y in the CRS's units, z in its z unit) → geodetic on the CRS's own
/// datum. For a geographic CRS, x is the longitude and y the latitude.
kernel::Result<GeodeticPoint> projected_to_geodetic(const Crs& crs, const kernel::Vec3& xyz);
/// Geodetic on the CRS's own datum → CRS coordinates.
kernel::Result<kernel::Vec3> geodetic_to_projected(const Crs& crs, const GeodeticPoint& point);
/// Geodetic → Earth-centred Earth-fixed on an ellipsoid (metres).
kernel::Vec3 geodetic_to_ecef(const Ellipsoid& ellipsoid, const GeodeticPoint& point);
/// ECEF → geodetic on an ellipsoid.
GeodeticPoint ecef_to_geodetic(const Ellipsoid& ellipsoid, const kernel::Vec3& ecef);
/// Geodetic on a datum → geodetic on WGS 84 (via ECEF and the datum's Helmert; unchanged for
/// null transformations). Errors: Unsupported when the datum's relation is unknown.
kernel::Result<GeodeticPoint> datum_to_wgs84(const GeodeticDatum& datum,
                                             const GeodeticPoint& point);
/// The inverse of datum_to_wgs84 (the exact inverse of the Helmert similarity).
kernel::Result<GeodeticPoint> wgs84_to_datum(const GeodeticDatum& datum,
                                             const GeodeticPoint& point);
/// CRS → CRS through WGS 84 (datum shifts as above). For tests, bounds and one-off points;
/// use a Georeferencer for bulk work.
kernel::Result<kernel::Vec3> transform_point(const Crs& from, const Crs& to,
                                             const kernel::Vec3& xyz);

/// Options of a Georeferencer.
struct GeoreferenceOptions {
  /// Added to z (after unit scaling) to turn gravity-related heights into ellipsoidal heights.
  double geoid_undulation_m = 0.0;
};

/// The tile-local frame: an east-north-up Cartesian frame tangent to the WGS 84 ellipsoid at
/// `origin`; x east, y north, z up, metres.
struct TileFrame {
  GeodeticPoint origin;            ///< on WGS 84
  kernel::Location local_to_ecef;  ///< exact: rotation + translation into WGS 84 ECEF
};

/// The best similarity "CRS coordinates → local" over a disc around the origin and how far it
/// is from the exact path there: for logs and for deciding when an approximation is good
/// enough. Never used by the Georeferencer itself.
struct SimilarityFit {
  Eigen::Matrix<double, 3, 4> source_to_local;  ///< s·R | t (s includes the CRS unit)
  double radius_m = 0.0;
  double max_error_m = 0.0;  ///< over a grid of points within radius_m of the origin
};

/// Transforms points of one CRS into one tile frame. Cheap to copy (shared immutable state).
class Georeferencer {
 public:
  /// Frame tangent at `frame_origin` (WGS 84). Errors: as validate_crs, Unsupported for a datum
  /// without a WGS 84 relation, InvalidArgument for a non-finite origin or |latitude| > 90.
  static kernel::Result<Georeferencer> create(const Crs& source, const GeodeticPoint& frame_origin,
                                              const GeoreferenceOptions& options = {});
  /// Frame tangent at a point given in the source CRS (e.g. a tile's centre).
  static kernel::Result<Georeferencer> create_at(const Crs& source, const kernel::Vec3& origin_xyz,
                                                 const GeoreferenceOptions& options = {});

  const Crs& crs() const;
  const TileFrame& frame() const;

  /// Source CRS coordinates → local ENU. A point outside the projection's domain gives NaNs.
  kernel::Vec3 to_local(const kernel::Vec3& source_xyz) const;
  /// Local ENU → source CRS coordinates. NaNs outside the domain.
  kernel::Vec3 to_source(const kernel::Vec3& local) const;
  /// As to_local, with the reason when the point is outside the domain.
  kernel::Result<kernel::Vec3> to_local_checked(const kernel::Vec3& source_xyz) const;
  kernel::Result<kernel::Vec3> to_source_checked(const kernel::Vec3& local) const;
  /// Bulk to_local; `out` must have the size of `in`. Stops at the first point outside the
  /// domain with InvalidArgument naming its index. O(n), no allocation.
  kernel::Status to_local(std::span<const kernel::Vec3> in, std::span<kernel::Vec3> out) const;

  /// Local ENU ↔ WGS 84 ECEF (the frame's Location) and geodetic.
  kernel::Vec3 local_to_ecef(const kernel::Vec3& local) const;
  kernel::Vec3 ecef_to_local(const kernel::Vec3& ecef) const;
  GeodeticPoint local_to_geodetic(const kernel::Vec3& local) const;
  kernel::Vec3 geodetic_to_local(const GeodeticPoint& wgs84) const;

  /// Least-squares similarity over a 21×21 grid of points within `radius_m` (metres) of the
  /// origin, in the source CRS. Errors: InvalidArgument for radius <= 0 or points outside the
  /// domain.
  kernel::Result<SimilarityFit> fit_similarity(double radius_m) const;

  struct Impl;

 private:
  explicit Georeferencer(std::shared_ptr<const Impl> impl) : impl_(std::move(impl)) {}
  std::shared_ptr<const Impl> impl_;
};

/// A terrestrial scanner's pose on the globe.
///
/// Scanner frame: x forward, y left, z up (right-handed), metres. Angles in degrees:
///  - heading: compass bearing of the forward axis, clockwise from true north (90 = east);
///  - pitch: elevation of the forward axis above the local horizon (positive = nose up);
///  - roll: rotation about the forward axis, positive when the right side goes down.
/// Scanner → local ENU at `position`: R = Rz(90° − heading) · Ry(−pitch) · Rx(roll).
struct ScannerPose {
  GeodeticPoint position;  ///< scanner origin on WGS 84 (ellipsoidal height)
  double heading_deg = 0.0;
  double pitch_deg = 0.0;
  double roll_deg = 0.0;
};

/// The rotation scanner frame → ENU at the scanner for heading/pitch/roll (see ScannerPose).
Eigen::Matrix3d scanner_rotation(double heading_deg, double pitch_deg, double roll_deg);

/// Places a scanner's points in a tile frame.
class ScannerPlacement {
 public:
  /// From a geodetic pose: an exact rigid motion, available as location().
  /// Errors: InvalidArgument for non-finite angles or a bad position.
  static kernel::Result<ScannerPlacement> from_pose(const Georeferencer& tile,
                                                    const ScannerPose& pose);
  /// From a 4×4 matrix mapping scanner coordinates (metres) to the tile's source CRS
  /// coordinates (its units): each point then takes the exact path, so location() is empty.
  /// Errors: InvalidArgument unless the last row is (0, 0, 0, 1) and the 3×3 part invertible.
  static kernel::Result<ScannerPlacement> from_projected_matrix(
      const Georeferencer& tile, const Eigen::Matrix4d& scanner_to_source);

  kernel::Vec3 to_local(const kernel::Vec3& scanner_point) const;
  kernel::Vec3 to_scanner(const kernel::Vec3& local) const;
  /// The scanner → local rigid motion when exact (geodetic poses).
  const std::optional<kernel::Location>& location() const { return location_; }

 private:
  ScannerPlacement() = default;
  std::optional<Georeferencer> tile_;
  std::optional<kernel::Location> location_;
  Eigen::Matrix4d matrix_ = Eigen::Matrix4d::Identity();
  Eigen::Matrix4d inverse_ = Eigen::Matrix4d::Identity();
};

}  // namespace csgtile::geo
