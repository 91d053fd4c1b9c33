#pragma once
/// \file
/// Location (paper §2.2): a 3×4 similarity transform Q = [s·R | t] placing a shape.

#include <cstddef>
#include <memory>

#include <Eigen/Core>
#include <Eigen/Geometry>  // cross products, rotations (and LU for determinants)

#include "csgtile/kernel/result.h"

namespace csgtile::kernel {

using Vec3 = Eigen::Vector3d;
using Vec2 = Eigen::Vector2d;
using Matrix34 = Eigen::Matrix<double, 3, 4>;

/// A similarity transform p' = s·R·p + t with R a proper rotation and s > 0.
///
/// The paper's conditions (1)–(2): the 3×3 part Q2 is non-singular and Q2 / cbrt(det Q2) is
/// orthogonal. We also require det Q2 > 0 (no mirroring: a mirror would turn solids inside
/// out). Values are immutable; composition returns a new Location.
///
/// A Location is a shared handle to its transform (OpenCASCADE's TopLoc_Location is one too):
/// the identity holds nothing, so the many child references at the identity inside a body
/// cost a null pointer, and composing with the identity shares the other side's transform.
class Location {
 public:
  /// The identity.
  Location();

  /// Checks conditions (1)–(2) with relative tolerance 1e-9 and re-orthonormalises R.
  /// Errors: InvalidLocation naming the failed condition (singular, not a similarity, mirror,
  /// non-finite entries).
  static Result<Location> from_matrix(const Matrix34& q);

  /// Rebuilds a location from the values rotation(), scale() and translation() returned,
  /// keeping them bit for bit (no re-orthonormalisation): the native format's reader needs
  /// write → read → write to be byte-identical. Errors: InvalidLocation for non-finite values,
  /// scale <= 0, or a rotation that is not proper orthogonal within relative 1e-9.
  static Result<Location> from_parts(const Eigen::Matrix3d& rotation, double scale,
                                     const Vec3& translation);

  static Location translation(const Vec3& t);
  /// Rotation by `angle` radians about the axis through `origin` with direction `axis`
  /// (normalised here; a zero axis gives the identity).
  static Location rotation(const Vec3& origin, const Vec3& axis, double angle);
  /// Uniform scale s > 0 about `center`. Precondition: s > 0 and finite.
  static Location scaling(double s, const Vec3& center = Vec3::Zero());

  /// Q = [s·R | t].
  Matrix34 matrix() const;
  const Eigen::Matrix3d& rotation() const { return t_ ? t_->rotation : identity_rotation(); }
  double scale() const { return t_ ? t_->scale : 1.0; }
  const Vec3& translation() const { return t_ ? t_->translation : zero_translation(); }
  /// Exactly the identity (scale 1, no translation, R = I).
  bool is_identity() const { return t_ == nullptr; }

  /// (*this * other)(p) = this(other(p)): `other` is applied first. This is how locations
  /// compose down the hierarchy (paper eq. 5): world = parent * child.
  Location operator*(const Location& other) const;
  Location inverse() const;

  Vec3 apply_point(const Vec3& p) const {
    return t_ ? Vec3(t_->scale * (t_->rotation * p) + t_->translation) : p;
  }
  /// Applies s·R (no translation): for derivatives.
  Vec3 apply_vector(const Vec3& v) const { return t_ ? Vec3(t_->scale * (t_->rotation * v)) : v; }
  /// Applies R only: for unit directions and normals.
  Vec3 apply_direction(const Vec3& d) const { return t_ ? Vec3(t_->rotation * d) : d; }

  /// Exact equality of the stored values (used for shape equality levels and hashing).
  bool operator==(const Location& other) const;
  bool operator!=(const Location& other) const { return !(*this == other); }
  /// Hash consistent with operator==.
  std::size_t hash() const;

 private:
  struct Transform {
    Eigen::Matrix3d rotation;
    double scale;
    Vec3 translation;
  };
  /// Null when the values are exactly the identity's.
  Location(const Eigen::Matrix3d& r, double s, const Vec3& t);
  static const Eigen::Matrix3d& identity_rotation();
  static const Vec3& zero_translation();
  std::shared_ptr<const Transform> t_;  ///< null: the identity
};

}  // namespace csgtile::kernel
