#include "csgtile/kernel/location.h"

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <cmath>
#include <cstring>
#include <functional>
#include <string>

namespace csgtile::kernel {

namespace {
// Relative tolerance of the similarity test (paper condition 2). Placements written with
// 10 significant digits (scene JSON) must pass; a 1e-6 shear must not.
constexpr double kSimilarityTolerance = 1e-9;

std::string format_double(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}
}  // namespace

Location::Location() = default;

// The identity is stored as nothing; any other transform has its signed zeros made +0
// (x + 0.0), so that equal transforms have equal bits whichever way they were composed (the
// native format deduplicates locations by their bits).
Location::Location(const Eigen::Matrix3d& r, double s, const Vec3& t) {
  if (s == 1.0 && t.isZero(0.0) && r == Eigen::Matrix3d::Identity()) return;
  const Eigen::Matrix3d rotation = r.array() + 0.0;
  const Vec3 translation = t.array() + 0.0;
  t_ = std::make_shared<const Transform>(Transform{rotation, s, translation});
}

const Eigen::Matrix3d& Location::identity_rotation() {
  static const Eigen::Matrix3d identity = Eigen::Matrix3d::Identity();
  return identity;
}

const Vec3& Location::zero_translation() {
  static const Vec3 zero = Vec3::Zero();
  return zero;
}

Result<Location> Location::from_matrix(const Matrix34& q) {
  if (!q.allFinite()) {
    return Error{ErrorCode::InvalidLocation, "location matrix has a non-finite entry"};
  }
  const Eigen::Matrix3d q2 = q.leftCols<3>();
  const double d = q2.determinant();
  const double norm = q2.norm();
  // Condition (1): non-singular, judged relative to the matrix's own size.
  if (norm == 0.0 || std::abs(d) <= 1e-12 * norm * norm * norm) {
    return Error{ErrorCode::InvalidLocation,
                 "location matrix is singular (det = " + format_double(d) + ")"};
  }
  if (d < 0.0) {
    return Error{ErrorCode::InvalidLocation,
                 "location matrix mirrors (det = " + format_double(d) +
                     " < 0); only rotations with a positive uniform scale are allowed"};
  }
  // Condition (2): Q3 = Q2 / cbrt(d) is orthogonal.
  const double s = std::cbrt(d);
  const Eigen::Matrix3d q3 = q2 / s;
  const double deviation =
      (q3.transpose() * q3 - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (deviation > kSimilarityTolerance) {
    return Error{ErrorCode::InvalidLocation,
                 "location matrix is not a similarity (rotation x uniform scale): "
                 "|Q3^T Q3 - I| = " +
                     format_double(deviation)};
  }
  // Nearest rotation (polar decomposition) so that composition does not drift.
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(q3, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d r = svd.matrixU() * svd.matrixV().transpose();
  return Location(r, s, q.col(3));
}

Result<Location> Location::from_parts(const Eigen::Matrix3d& rotation, double scale,
                                      const Vec3& translation) {
  if (!rotation.allFinite() || !std::isfinite(scale) || !translation.allFinite()) {
    return Error{ErrorCode::InvalidLocation, "location part has a non-finite entry"};
  }
  if (!(scale > 0.0)) {
    return Error{ErrorCode::InvalidLocation,
                 "location scale " + format_double(scale) + " is not > 0"};
  }
  const double deviation =
      (rotation.transpose() * rotation - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (deviation > kSimilarityTolerance) {
    return Error{ErrorCode::InvalidLocation,
                 "location rotation is not orthogonal: |R^T R - I| = " + format_double(deviation)};
  }
  if (rotation.determinant() <= 0.0) {
    return Error{ErrorCode::InvalidLocation, "location rotation mirrors (det <= 0)"};
  }
  return Location(rotation, scale, translation);
}

Location Location::translation(const Vec3& t) {
  return Location(Eigen::Matrix3d::Identity(), 1.0, t);
}

Location Location::rotation(const Vec3& origin, const Vec3& axis, double angle) {
  if (axis.norm() == 0.0) return Location();
  const Eigen::Matrix3d r = Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
  return Location(r, 1.0, origin - r * origin);
}

Location Location::scaling(double s, const Vec3& center) {
  return Location(Eigen::Matrix3d::Identity(), s, center - s * center);
}

Matrix34 Location::matrix() const {
  Matrix34 m;
  m.leftCols<3>() = scale() * rotation();
  m.col(3) = translation();
  return m;
}

// Composing with the identity shares the other side's transform: no arithmetic, no copy.
Location Location::operator*(const Location& other) const {
  if (!other.t_) return *this;
  if (!t_) return other;
  const Transform& a = *t_;
  const Transform& b = *other.t_;
  return Location(a.rotation * b.rotation, a.scale * b.scale,
                  a.scale * (a.rotation * b.translation) + a.translation);
}

Location Location::inverse() const {
  if (!t_) return *this;
  const Eigen::Matrix3d rt = t_->rotation.transpose();
  return Location(rt, 1.0 / t_->scale, -(rt * t_->translation) / t_->scale);
}

bool Location::operator==(const Location& other) const {
  if (t_ == other.t_) return true;
  if (!t_ || !other.t_) return false;  // the identity is never stored
  return t_->scale == other.t_->scale && t_->translation == other.t_->translation &&
         t_->rotation == other.t_->rotation;
}

std::size_t Location::hash() const {
  if (!t_) return 0;
  std::size_t h = std::hash<double>{}(t_->scale);
  auto mix = [&h](double v) {
    h ^= std::hash<double>{}(v) + 0x9e3779b97f4a7c15ULL + (h << 6) + (h >> 2);
  };
  for (int i = 0; i < 3; ++i) {
    mix(t_->translation[i]);
    for (int j = 0; j < 3; ++j) mix(t_->rotation(i, j));
  }
  return h;
}

}  // namespace csgtile::kernel
