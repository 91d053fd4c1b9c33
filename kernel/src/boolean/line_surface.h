#pragma once
/// \file
/// Intersections of a straight line with the kernel's surfaces (their roots by polynomial.h).
/// Private to the Boolean unit (the point classifier casts rays with it).

#include <cstddef>
#include <vector>

#include "csgtile/kernel/polynomial.h"
#include "csgtile/kernel/surface.h"

namespace csgtile::kernel::detail {

/// Where a line meets a surface.
struct LineSurfaceHit {
  double t;      ///< line parameter
  Vec2 uv;       ///< surface parameters there (periodic ones in any one period)
  bool tangent;  ///< a multiple root, or the line crosses the surface at a grazing angle
};

/// All intersections of a line with a surface, and whether they could be isolated.
struct LineSurfaceIntersection {
  std::vector<LineSurfaceHit> hits;
  /// The line lies on the surface (or along one of its rulings, or nearly perpendicular to a
  /// revolution axis where the equations lose their conditioning): the hits are not a finite,
  /// trustworthy set and a caller casting rays should cast another one.
  bool degenerate = false;
};

/// Cosine between a line's direction and the surface normal below which a crossing counts as
/// grazing (LineSurfaceHit::tangent).
inline constexpr double kGrazingCosine = 1e-6;

/// Intersects the line origin + t·direction (|direction| = 1) with `surface`, all in the
/// surface's own frame, for t in [t0, t1] (a finite interval). Closed forms for plane,
/// cylinder, cone and sphere (quadratics), extrusions (linear, conic and polyline bases) and
/// revolutions of lines and polylines (quadratics per segment); the torus and revolutions of
/// conics through a quartic solved by polynomial_roots(). `range` bounds the surface
/// parameters of interest (the face's parameter box): swept surfaces only look for their
/// basis / meridian parameter there. `tolerance` decides when the line lies on the surface.
/// The result is cleared first. Thread-safe; allocation only in `out`.
void intersect_line_surface(const Surface& surface, const Vec3& origin, const Vec3& direction,
                            double t0, double t1, const ParamBox& range, double tolerance,
                            LineSurfaceIntersection& out);

}  // namespace csgtile::kernel::detail
