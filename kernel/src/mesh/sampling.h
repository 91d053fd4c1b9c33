#pragma once
// Parameter sampling of curves and of a surface's iso-parameter rows within a chordal and an
// angular tolerance. Everything here works in the geometry's own (body) frame: callers
// divide world tolerances by the location's scale.

#include <cstddef>
#include <functional>
#include <limits>
#include <utility>
#include <vector>

#include "csgtile/kernel/curve.h"
#include "csgtile/kernel/surface.h"

namespace csgtile::kernel::detail {

/// Upper bound on the segments of one curve or row; beyond it tessellation fails instead of
/// exhausting memory.
inline constexpr std::size_t kMaxSegments = std::size_t{1} << 20;

/// Largest turning angle of a circular arc of radius `radius` whose sagitta is at most
/// `chordal`, capped by `angular`.
double allowed_turn(double radius, double chordal, double angular);

/// First and second derivative of a parametric curve at t.
using CurveDerivatives = std::function<std::pair<Vec3, Vec3>(double)>;

/// Largest parameter step over [t0, t1] that keeps every chord within `chordal` of the
/// curve and turns by at most `angular` per segment, from the curvature sampled at 65 points
/// (with a 5% margin for curvature peaks between samples).
double uniform_step(const CurveDerivatives& derivatives, double t0, double t1, double chordal,
                    double angular);

/// Number of equal steps of at most `step` over `span` (at least 1); 0 when over
/// kMaxSegments or when step is not positive.
std::size_t segments_for(double span, double step);

/// Sample parameters of a curve over [first, last] (first and last included, increasing):
/// lines their ends, circles an exact uniform subdivision, polylines their breakpoints,
/// other curves a uniform one from uniform_step(). Curved kinds also keep steps at most
/// `max_step` (a face's demand). Empty when over kMaxSegments.
std::vector<double> curve_parameters(const Curve& curve, double first, double last, double chordal,
                                     double angular,
                                     double max_step = std::numeric_limits<double>::infinity());

/// True for surfaces whose u is the angle about an axis (cylinder, cone, sphere, torus,
/// revolution): their rows v = const are circles of radius |∂S/∂u|.
bool revolution_like(const Surface& surface);

/// Largest u step on the row v = const, u in [u0, u1]: exact for revolution-like surfaces,
/// uniform_step() on the row curve (second derivative by central differences) otherwise.
double row_step(const Surface& surface, double v, double u0, double u1, double chordal,
                double angular);

/// Number of equal u steps for that row; 0 when over kMaxSegments.
std::size_t row_segment_count(const Surface& surface, double v, double u0, double u1,
                              double chordal, double angular);

}  // namespace csgtile::kernel::detail
