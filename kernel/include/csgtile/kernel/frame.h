#pragma once
/// \file
/// Right-handed orthonormal frame used to place elementary curves and surfaces.

#include "csgtile/kernel/location.h"

namespace csgtile::kernel {

/// Origin plus orthonormal right-handed axes x, y, z = x × y.
struct Frame {
  Vec3 origin = Vec3::Zero();
  Vec3 x = Vec3::UnitX();
  Vec3 y = Vec3::UnitY();
  Vec3 z = Vec3::UnitZ();

  /// Frame with the given origin and z axis; x is `x_hint` made orthogonal to z (or any
  /// perpendicular direction when the hint is parallel to z). Directions are normalised.
  static Frame from_z(const Vec3& origin, const Vec3& z, const Vec3& x_hint = Vec3::UnitX());

  /// The frame moved by a location (origin as a point, axes as directions).
  Frame transformed(const Location& loc) const;
};

}  // namespace csgtile::kernel
