#include "csgtile/kernel/frame.h"

#include <cmath>

#include "geometry/geometry_internal.h"

namespace csgtile::kernel {

namespace detail {

Vec3 any_perpendicular(const Vec3& d) {
  // Crossing with the coordinate axis least aligned with d keeps the result well
  // conditioned (|d × e| ≥ sqrt(2/3)) and deterministic.
  const Vec3 a = d.cwiseAbs();
  Vec3 axis = Vec3::UnitX();
  if (a.y() < a.x() && a.y() <= a.z()) {
    axis = Vec3::UnitY();
  } else if (a.z() < a.x() && a.z() < a.y()) {
    axis = Vec3::UnitZ();
  }
  const Vec3 p = d.cross(axis);
  const double n = p.norm();
  return n > 0.0 ? Vec3(p / n) : Vec3::UnitX();
}

}  // namespace detail

Frame Frame::from_z(const Vec3& origin, const Vec3& z, const Vec3& x_hint) {
  Frame f;
  f.origin = origin;
  const double zn = z.norm();
  f.z = zn > 0.0 ? Vec3(z / zn) : Vec3::UnitZ();
  // Gram–Schmidt on the hint; a hint (nearly) parallel to z carries no usable direction,
  // judged relative to its own length so that the choice does not depend on units.
  Vec3 x = x_hint - x_hint.dot(f.z) * f.z;
  const double xn = x.norm();
  if (xn > 1e-12 * x_hint.norm()) {
    // A second projection removes what cancellation left of z when the hint is nearly
    // parallel to it ("twice is enough").
    x /= xn;
    x -= x.dot(f.z) * f.z;
    f.x = x.normalized();
  } else {
    f.x = detail::any_perpendicular(f.z);
  }
  f.y = f.z.cross(f.x);
  return f;
}

Frame Frame::transformed(const Location& loc) const {
  Frame f;
  f.origin = loc.apply_point(origin);
  f.x = loc.apply_direction(x);
  f.y = loc.apply_direction(y);
  f.z = loc.apply_direction(z);
  return f;
}

}  // namespace csgtile::kernel
