#pragma once
// Numeric surface–surface intersection by marching, for the surface pairs that have no
// closed-form section (issue 4 item 2): skew or unequal crossing cylinders, oblique plane
// sections of cones and tori, cones and tori off a common axis, spheres cut by surfaces with
// no common axis. Not API.
//
// Every branch inside a region is traced as a polyline whose vertices lie on both surfaces
// (Newton-corrected to far below the tolerance), with the (u, v) of each vertex on each
// surface: the section edge is then a PolylineCurve with Polyline2d pcurves that share its
// parameter (vertex i at t = i). The step adapts so that every chord, and the image of every
// pcurve segment on its surface, stays within `sag` of the exact curve: the edges get that
// measured deviation as their tolerance.
//
// Seeds: a lattice over the region, each point pulled onto the intersection by a minimum-
// norm Newton iteration in the four parameters; a seed landing on a traced branch is
// dropped. Components smaller than the lattice spacing (region diagonal / 16) can be missed
// when no lattice point lies in their basin; tangent contacts are reported, not traced.

#include <optional>
#include <string>
#include <vector>

#include "csgtile/kernel/bounding_box.h"
#include "csgtile/kernel/curve.h"
#include "csgtile/kernel/surface.h"

namespace csgtile::kernel::detail {

struct MarchedCurve {
  std::vector<Vec3> points;
  std::vector<Vec2> uv_a, uv_b;  ///< parameters of each point on surface a and b
  bool closed = false;           ///< points.front() == points.back(): a loop
  double deviation = 0.0;        ///< largest chord / pcurve distance from the exact curve
};

struct MarchResult {
  bool ok = true;
  std::string reason;  ///< when !ok: where and why tracing stopped (tangency, singularity)
  std::vector<MarchedCurve> curves;
};

/// Every branch of a ∩ b that meets `region`, each traced until it closes or leaves the
/// region (its last point is then the first one outside). `tolerance` decides when a point
/// is on both surfaces (Newton stops far below it); `sag` (>= tolerance) bounds the chordal
/// deviation. Deterministic.
MarchResult march_intersection(const Surface& a, const Surface& b, const BoundingBox& region,
                               double tolerance, double sag);

/// A known section curve c over [t0, t1] (closed form) turned into a traced one, for faces
/// on which its pcurve has no exact form (a circle on a sphere whose poles were turned away
/// from it): points of c, refined until every chord and both pcurve segments' images stay
/// within `sag` of c. Null when that needs more than 100 000 points (a pole on the way).
std::optional<MarchedCurve> sample_section(const Curve& c, double t0, double t1, const Surface& a,
                                           const Surface& b, double sag);

}  // namespace csgtile::kernel::detail
