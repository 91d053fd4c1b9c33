// Georeferencing: free conversion functions, the tile-frame Georeferencer and scanner poses.
//
// Every GeographicLib call is reached through detail::CrsMath / DatumShift, which throw;
// this file is the wrapper where exceptions stop: checked calls return InvalidArgument with
// the library's message, bulk calls return NaNs (documented in the header).

#include "csgtile/geo/georeference.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <GeographicLib/Geocentric.hpp>
#include <GeographicLib/LocalCartesian.hpp>

#include "crs/crs_internal.h"
#include "crs/geodesy.h"

namespace csgtile::geo {

using kernel::Error;
using kernel::ErrorCode;
using kernel::Result;
using kernel::Status;
using kernel::Vec3;

namespace {

Error domain_error(const Crs& crs, const Vec3& p, const std::exception& e) {
  return Error{ErrorCode::InvalidArgument, "point (" + detail::format_number(p.x()) + ", " +
                                               detail::format_number(p.y()) + ", " +
                                               detail::format_number(p.z()) + ") of " +
                                               describe_crs(crs) + ": " + e.what()};
}

Vec3 nan_vector() {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  return Vec3(nan, nan, nan);
}

bool finite(const Vec3& v) {
  return std::isfinite(v.x()) && std::isfinite(v.y()) && std::isfinite(v.z());
}

Status check_geodetic(const GeodeticPoint& g, const char* what) {
  if (!std::isfinite(g.latitude_deg) || !std::isfinite(g.longitude_deg) ||
      !std::isfinite(g.height_m) || std::fabs(g.latitude_deg) > 90.0) {
    return Status(ErrorCode::InvalidArgument,
                  std::string(what) + " must be finite with |latitude| <= 90");
  }
  return Status();
}

}  // namespace

Result<GeodeticPoint> projected_to_geodetic(const Crs& crs, const Vec3& xyz) {
  auto math = detail::CrsMath::create(crs);
  if (!math.ok()) return math.error();
  try {
    return math.value()->to_geodetic(xyz);
  } catch (const std::exception& e) {
    return domain_error(crs, xyz, e);
  }
}

Result<Vec3> geodetic_to_projected(const Crs& crs, const GeodeticPoint& point) {
  auto math = detail::CrsMath::create(crs);
  if (!math.ok()) return math.error();
  try {
    return math.value()->from_geodetic(point);
  } catch (const std::exception& e) {
    return domain_error(crs, Vec3(point.longitude_deg, point.latitude_deg, point.height_m), e);
  }
}

Vec3 geodetic_to_ecef(const Ellipsoid& ellipsoid, const GeodeticPoint& point) {
  const GeographicLib::Geocentric earth(ellipsoid.semi_major_m, ellipsoid.flattening());
  Vec3 x;
  earth.Forward(point.latitude_deg, point.longitude_deg, point.height_m, x.x(), x.y(), x.z());
  return x;
}

GeodeticPoint ecef_to_geodetic(const Ellipsoid& ellipsoid, const Vec3& ecef) {
  const GeographicLib::Geocentric earth(ellipsoid.semi_major_m, ellipsoid.flattening());
  GeodeticPoint p;
  earth.Reverse(ecef.x(), ecef.y(), ecef.z(), p.latitude_deg, p.longitude_deg, p.height_m);
  return p;
}

Result<GeodeticPoint> datum_to_wgs84(const GeodeticDatum& datum, const GeodeticPoint& point) {
  auto shift = detail::DatumShift::create(datum);
  if (!shift.ok()) return shift.error();
  if (shift.value().is_identity()) return point;
  const Vec3 ecef = shift.value().to_wgs84_ecef(point);
  GeodeticPoint out;
  GeographicLib::Geocentric::WGS84().Reverse(ecef.x(), ecef.y(), ecef.z(), out.latitude_deg,
                                             out.longitude_deg, out.height_m);
  return out;
}

Result<GeodeticPoint> wgs84_to_datum(const GeodeticDatum& datum, const GeodeticPoint& point) {
  auto shift = detail::DatumShift::create(datum);
  if (!shift.ok()) return shift.error();
  if (shift.value().is_identity()) return point;
  Vec3 ecef;
  GeographicLib::Geocentric::WGS84().Forward(point.latitude_deg, point.longitude_deg,
                                             point.height_m, ecef.x(), ecef.y(), ecef.z());
  return shift.value().from_wgs84_ecef(ecef);
}

Result<Vec3> transform_point(const Crs& from, const Crs& to, const Vec3& xyz) {
  auto geodetic = projected_to_geodetic(from, xyz);
  if (!geodetic.ok()) return geodetic.error();
  // Skip the hub when both sides share the datum (no round-off, no Helmert, and datums
  // without a WGS 84 relation still convert among their own projections).
  Crs from_datum;
  Crs to_datum;
  from_datum.datum = from.datum;
  to_datum.datum = to.datum;
  const bool same_datum = !crs_difference(from_datum, to_datum).has_value();
  if (same_datum) return geodetic_to_projected(to, geodetic.value());
  auto wgs84 = datum_to_wgs84(from.datum, geodetic.value());
  if (!wgs84.ok()) return wgs84.error();
  auto target = wgs84_to_datum(to.datum, wgs84.value());
  if (!target.ok()) return target.error();
  return geodetic_to_projected(to, target.value());
}

// ---- Georeferencer -----------------------------------------------------------------------

struct Georeferencer::Impl {
  std::shared_ptr<const detail::CrsMath> math;
  detail::DatumShift shift;
  GeoreferenceOptions options;
  TileFrame frame;
  Eigen::Matrix3d rotation;  // ENU → ECEF
  Vec3 origin_ecef;
  GeographicLib::LocalCartesian local;  // used on the identity-datum path

  // Both throw on points outside the domain.
  Vec3 forward(const Vec3& p) const { return forward_geodetic(math->to_geodetic(p)); }
  // The part of forward after the CRS's own coordinates: geodetic on its datum → local.
  Vec3 forward_geodetic(GeodeticPoint g) const {
    g.height_m += options.geoid_undulation_m;
    Vec3 out;
    if (shift.is_identity()) {
      local.Forward(g.latitude_deg, g.longitude_deg, g.height_m, out.x(), out.y(), out.z());
    } else {
      out = rotation.transpose() * (shift.to_wgs84_ecef(g) - origin_ecef);
    }
    return out;
  }
  Vec3 reverse(const Vec3& l) const {
    GeodeticPoint g;
    if (shift.is_identity()) {
      local.Reverse(l.x(), l.y(), l.z(), g.latitude_deg, g.longitude_deg, g.height_m);
    } else {
      g = shift.from_wgs84_ecef(rotation * l + origin_ecef);
    }
    g.height_m -= options.geoid_undulation_m;
    return math->from_geodetic(g);
  }
};

Result<Georeferencer> Georeferencer::create(const Crs& source, const GeodeticPoint& origin,
                                            const GeoreferenceOptions& options) {
  if (auto s = check_geodetic(origin, "frame origin"); !s.ok()) return s.error();
  if (!std::isfinite(options.geoid_undulation_m) || std::fabs(options.geoid_undulation_m) > 200.0) {
    return Error{ErrorCode::InvalidArgument, "geoid undulation must be finite and within ±200 m"};
  }
  auto math = detail::CrsMath::create(source);
  if (!math.ok()) return math.error();
  auto shift = detail::DatumShift::create(source.datum);
  if (!shift.ok()) return shift.error();

  auto impl = std::make_shared<Impl>();
  impl->math = math.value();
  impl->shift = shift.value();
  impl->options = options;
  impl->frame.origin = origin;
  impl->local.Reset(origin.latitude_deg, origin.longitude_deg, origin.height_m);
  impl->rotation = detail::enu_rotation(origin.latitude_deg, origin.longitude_deg);
  GeographicLib::Geocentric::WGS84().Forward(origin.latitude_deg, origin.longitude_deg,
                                             origin.height_m, impl->origin_ecef.x(),
                                             impl->origin_ecef.y(), impl->origin_ecef.z());
  auto location = kernel::Location::from_parts(impl->rotation, 1.0, impl->origin_ecef);
  if (!location.ok()) return location.error();
  impl->frame.local_to_ecef = location.value();
  return Georeferencer(std::move(impl));
}

Result<Georeferencer> Georeferencer::create_at(const Crs& source, const Vec3& origin_xyz,
                                               const GeoreferenceOptions& options) {
  auto math = detail::CrsMath::create(source);
  if (!math.ok()) return math.error();
  auto shift = detail::DatumShift::create(source.datum);
  if (!shift.ok()) return shift.error();
  try {
    GeodeticPoint g = math.value()->to_geodetic(origin_xyz);
    g.height_m += options.geoid_undulation_m;
    if (!shift.value().is_identity()) {
      const Vec3 ecef = shift.value().to_wgs84_ecef(g);
      GeographicLib::Geocentric::WGS84().Reverse(ecef.x(), ecef.y(), ecef.z(), g.latitude_deg,
                                                 g.longitude_deg, g.height_m);
    }
    return create(source, g, options);
  } catch (const std::exception& e) {
    return domain_error(source, origin_xyz, e);
  }
}

const Crs& Georeferencer::crs() const { return impl_->math->crs(); }
const TileFrame& Georeferencer::frame() const { return impl_->frame; }

Vec3 Georeferencer::to_local(const Vec3& p) const {
  try {
    return impl_->forward(p);
  } catch (const std::exception&) {
    return nan_vector();
  }
}

Vec3 Georeferencer::to_source(const Vec3& l) const {
  try {
    return impl_->reverse(l);
  } catch (const std::exception&) {
    return nan_vector();
  }
}

Result<Vec3> Georeferencer::to_local_checked(const Vec3& p) const {
  try {
    Vec3 out = impl_->forward(p);
    if (!finite(out)) throw detail::DomainError("non-finite result");
    return out;
  } catch (const std::exception& e) {
    return domain_error(crs(), p, e);
  }
}

Result<Vec3> Georeferencer::to_source_checked(const Vec3& l) const {
  try {
    Vec3 out = impl_->reverse(l);
    if (!finite(out)) throw detail::DomainError("non-finite result");
    return out;
  } catch (const std::exception& e) {
    return Error{ErrorCode::InvalidArgument,
                 "local point (" + detail::format_number(l.x()) + ", " +
                     detail::format_number(l.y()) + ", " + detail::format_number(l.z()) +
                     ") has no coordinates in " + describe_crs(crs()) + ": " + e.what()};
  }
}

Status Georeferencer::to_local(std::span<const Vec3> in, std::span<Vec3> out) const {
  if (in.size() != out.size()) {
    return Status(ErrorCode::InvalidArgument, "to_local: input and output sizes differ (" +
                                                  std::to_string(in.size()) + " vs " +
                                                  std::to_string(out.size()) + ")");
  }
  const Impl& impl = *impl_;
  // The CRS's own coordinates → geodetic in batches (PROJ transforms a batch per call), the
  // rest point by point; a point that fails is redone alone for its reason.
  constexpr std::size_t kBatch = 4096;
  std::vector<GeodeticPoint> geodetic(std::min(kBatch, in.size()));
  for (std::size_t start = 0; start < in.size(); start += kBatch) {
    const std::size_t n = std::min(kBatch, in.size() - start);
    impl.math->to_geodetic_many(in.subspan(start, n), std::span(geodetic).first(n));
    for (std::size_t k = 0; k < n; ++k) {
      const std::size_t i = start + k;
      try {
        const GeodeticPoint& g = geodetic[k];
        out[i] = std::isfinite(g.latitude_deg) ? impl.forward_geodetic(g) : impl.forward(in[i]);
        if (!finite(out[i])) throw detail::DomainError("non-finite result");
      } catch (const std::exception& e) {
        return Status(ErrorCode::InvalidArgument,
                      "point " + std::to_string(i) + ": " + domain_error(crs(), in[i], e).message);
      }
    }
  }
  return Status();
}

Vec3 Georeferencer::local_to_ecef(const Vec3& local) const {
  return impl_->frame.local_to_ecef.apply_point(local);
}

Vec3 Georeferencer::ecef_to_local(const Vec3& ecef) const {
  return impl_->rotation.transpose() * (ecef - impl_->origin_ecef);
}

GeodeticPoint Georeferencer::local_to_geodetic(const Vec3& local) const {
  GeodeticPoint g;
  impl_->local.Reverse(local.x(), local.y(), local.z(), g.latitude_deg, g.longitude_deg,
                       g.height_m);
  return g;
}

Vec3 Georeferencer::geodetic_to_local(const GeodeticPoint& g) const {
  Vec3 out;
  impl_->local.Forward(g.latitude_deg, g.longitude_deg, g.height_m, out.x(), out.y(), out.z());
  return out;
}

Result<SimilarityFit> Georeferencer::fit_similarity(double radius_m) const {
  if (!(radius_m > 0) || !std::isfinite(radius_m)) {
    return Error{ErrorCode::InvalidArgument, "fit_similarity: radius must be positive"};
  }
  // Sample a square grid (in metres of the local frame) around the origin, keep the disc.
  constexpr int kSide = 21;
  Eigen::Matrix3Xd source(3, kSide * kSide);
  Eigen::Matrix3Xd local(3, kSide * kSide);
  int count = 0;
  for (int i = 0; i < kSide; ++i) {
    for (int j = 0; j < kSide; ++j) {
      const double x = radius_m * (2.0 * i / (kSide - 1) - 1.0);
      const double y = radius_m * (2.0 * j / (kSide - 1) - 1.0);
      if (x * x + y * y > radius_m * radius_m * (1 + 1e-12)) continue;
      const Vec3 l(x, y, 0.0);
      auto s = to_source_checked(l);
      if (!s.ok()) return s.error();
      source.col(count) = s.value();
      local.col(count) = l;
      ++count;
    }
  }
  source.conservativeResize(3, count);
  local.conservativeResize(3, count);
  // Heights vary little over a tangent-plane grid; add a raised copy so the fit sees z.
  Eigen::Matrix3Xd source2(3, 2 * count), local2(3, 2 * count);
  source2.leftCols(count) = source;
  local2.leftCols(count) = local;
  for (int k = 0; k < count; ++k) {
    const Vec3 l = local.col(k) + Vec3(0, 0, radius_m * 0.1);
    auto s = to_source_checked(l);
    if (!s.ok()) return s.error();
    source2.col(count + k) = s.value();
    local2.col(count + k) = l;
  }
  const Eigen::Matrix4d t = Eigen::umeyama(source2, local2, true);
  SimilarityFit fit;
  fit.source_to_local = t.topRows<3>();
  fit.radius_m = radius_m;
  for (int k = 0; k < 2 * count; ++k) {
    const Vec3 predicted =
        fit.source_to_local.leftCols<3>() * source2.col(k) + fit.source_to_local.col(3);
    fit.max_error_m = std::max(fit.max_error_m, (predicted - local2.col(k)).norm());
  }
  return fit;
}

// ---- scanners ----------------------------------------------------------------------------

Eigen::Matrix3d scanner_rotation(double heading_deg, double pitch_deg, double roll_deg) {
  const double deg = detail::kDegree;
  const Eigen::Matrix3d yaw =
      Eigen::AngleAxisd((90.0 - heading_deg) * deg, Vec3::UnitZ()).toRotationMatrix();
  const Eigen::Matrix3d pitch =
      Eigen::AngleAxisd(-pitch_deg * deg, Vec3::UnitY()).toRotationMatrix();
  const Eigen::Matrix3d roll = Eigen::AngleAxisd(roll_deg * deg, Vec3::UnitX()).toRotationMatrix();
  return yaw * pitch * roll;
}

Result<ScannerPlacement> ScannerPlacement::from_pose(const Georeferencer& tile,
                                                     const ScannerPose& pose) {
  if (auto s = check_geodetic(pose.position, "scanner position"); !s.ok()) return s.error();
  if (!std::isfinite(pose.heading_deg) || !std::isfinite(pose.pitch_deg) ||
      !std::isfinite(pose.roll_deg)) {
    return Error{ErrorCode::InvalidArgument, "scanner heading, pitch and roll must be finite"};
  }
  // scanner → ENU at the scanner → WGS 84 ECEF → tile ENU: three rigid motions, so one exact
  // Location (the two ENU frames differ by a rotation and a translation of the same ECEF).
  const GeodeticPoint& p = pose.position;
  const Eigen::Matrix3d scanner_enu = detail::enu_rotation(p.latitude_deg, p.longitude_deg);
  Vec3 scanner_ecef;
  GeographicLib::Geocentric::WGS84().Forward(p.latitude_deg, p.longitude_deg, p.height_m,
                                             scanner_ecef.x(), scanner_ecef.y(), scanner_ecef.z());
  const Eigen::Matrix3d tile_enu = tile.frame().local_to_ecef.rotation();
  const Eigen::Matrix3d rotation =
      tile_enu.transpose() * scanner_enu *
      scanner_rotation(pose.heading_deg, pose.pitch_deg, pose.roll_deg);
  const Vec3 translation = tile.ecef_to_local(scanner_ecef);
  auto location =
      kernel::Location::from_matrix((kernel::Matrix34() << rotation, translation).finished());
  if (!location.ok()) return location.error();
  ScannerPlacement placement;
  placement.location_ = location.value();
  return placement;
}

Result<ScannerPlacement> ScannerPlacement::from_projected_matrix(const Georeferencer& tile,
                                                                 const Eigen::Matrix4d& m) {
  if (!m.allFinite())
    return Error{ErrorCode::InvalidArgument, "scanner matrix has non-finite entries"};
  if (m(3, 0) != 0.0 || m(3, 1) != 0.0 || m(3, 2) != 0.0 || m(3, 3) != 1.0) {
    return Error{ErrorCode::InvalidArgument, "scanner matrix: the last row must be (0, 0, 0, 1)"};
  }
  const double det = m.topLeftCorner<3, 3>().determinant();
  if (!(std::fabs(det) > 1e-12))
    return Error{ErrorCode::InvalidArgument, "scanner matrix: singular 3×3 part"};
  ScannerPlacement placement;
  placement.tile_ = tile;
  placement.matrix_ = m;
  placement.inverse_ = m.inverse();
  return placement;
}

Vec3 ScannerPlacement::to_local(const Vec3& s) const {
  if (location_) return location_->apply_point(s);
  const Vec3 source = matrix_.topLeftCorner<3, 3>() * s + matrix_.topRightCorner<3, 1>();
  return tile_->to_local(source);
}

Vec3 ScannerPlacement::to_scanner(const Vec3& l) const {
  if (location_) return location_->inverse().apply_point(l);
  const Vec3 source = tile_->to_source(l);
  return inverse_.topLeftCorner<3, 3>() * source + inverse_.topRightCorner<3, 1>();
}

}  // namespace csgtile::geo
