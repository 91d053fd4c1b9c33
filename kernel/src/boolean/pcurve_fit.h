#pragma once
// Exact pcurves for Boolean section edges: the (u, v) image of a curve on a surface, found as
// a trig-linear curve c + cos t·a + sin t·b + t·d and accepted only when it reproduces the
// 3D curve within a tight tolerance everywhere on the range.

#include "csgtile/kernel/curve.h"
#include "csgtile/kernel/curve2d.h"
#include "csgtile/kernel/surface.h"

namespace csgtile::kernel::detail {

/// The pcurve of `curve` over [t0, t1] on `surface` (both in one frame), or null when no
/// trig-linear pcurve matches within `tolerance` at every check point. On a plane the pcurve
/// is the exact affine projection; elsewhere it is fitted to inverted samples (periodic
/// parameters unwrapped) and verified at 97 points (a line on a plane: at its two ends, which
/// bound its deviation).
Curve2dPtr fit_pcurve(const Curve& curve, double t0, double t1, const Surface& surface,
                      double tolerance);

/// `value` moved by whole periods to the one nearest `reference` (unchanged when period <= 0):
/// unwrapping periodic parameters along a curve.
double nearest_periodic(double value, double reference, double period);

/// The same pcurve moved by `offset` in the parameter plane (periodic shifts).
Curve2dPtr shift_pcurve(const Curve2dPtr& pcurve, const Vec2& offset);

/// Largest distance between surface(pcurve(t)) and curve(t) over `samples` points of [t0, t1].
double pcurve_deviation(const Curve& curve, const Curve2d& pcurve, double t0, double t1,
                        const Surface& surface, int samples = 97);

}  // namespace csgtile::kernel::detail
