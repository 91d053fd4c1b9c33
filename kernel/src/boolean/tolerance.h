#pragma once
/// \file
/// The Boolean engine's tolerance model: every tolerance and numerical threshold the engine
/// (boolean/*) uses, named in one place, with what it guards. Private to the kernel.
///
/// Exact predicates and tolerances: who decides what
/// --------------------------------------------------
/// The engine asks two kinds of questions, and answers each with its own tool.
///
///  * Coincidence — are two things the same within the modelling accuracy? Two vertices one
///    point, a point on a face, an edge lying in a face, two planes one plane, two directions
///    parallel, a curve running along another. The geometry comes from rounded computations
///    and from inputs that carry their own tolerances, so these are never decided exactly:
///    the linear tolerance of the operation (BooleanOptions::tolerance, widened per entity by
///    the input shapes' own edge / vertex tolerances where those are known, e.g. the edge
///    bands of the classifier) decides them, through ToleranceModel below.
///  * Sides and orientation — given the doubles actually stored, on which side of a line or a
///    plane does a point lie, does a segment cross a ray, does a loop turn clockwise, in which
///    angular order do the curves leave a node, do two straight pcurves cross? These are
///    decided by the exact predicates (predicates/predicates.h) on those doubles, so that the
///    answers are consistent with one another (a point is never left of a segment in one test
///    and right of it in the next, crossing parities always add up).
///
/// Tolerance first, exact second: a decision first asks whether the things coincide within
/// tolerance (then the point is on the boundary, the vertices merge, the planes are one, the
/// ray is recast); only when they do not does the exact predicate decide the side. Outside the
/// tolerance band the exact sign agrees with any careful floating-point one; the exact
/// predicate matters where a band is deliberately tiny or absent — the even–odd parity of a
/// sampled polygon, the ordering of nearly tangent curves at a node, the orientation of a
/// sliver loop — where any answer is acceptable as long as every test gives the same one.
///
/// Curved decisions (roots of ray–surface equations, Newton refinement of pcurve crossings,
/// bulges of arcs around their chords) stay in this model as well: a geometric threshold is a
/// ToleranceModel decision or a named fraction of a tolerance, and the remaining constants are
/// numerical (rounding-noise levels, iteration limits, sampling densities), named as such.

#include <algorithm>
#include <cmath>

#include "csgtile/kernel/location.h"

namespace csgtile::kernel::detail {

// ---- Coincidence: the model ------------------------------------------------------------------

/// The tolerance model of one decision context: `length` is the world linear tolerance, `size`
/// the extent over which directions are compared (the model's or the problem's size), so that
/// two directions are "the same" when lines along them drift apart by less than `length` over
/// `size`.
struct ToleranceModel {
  double length;
  double size;

  /// A distance (or a difference of distances) that is zero within tolerance.
  bool negligible(double distance) const { return std::abs(distance) <= length; }
  /// The sine of an angle that moves points less than the tolerance over the size.
  bool negligible_angle(double sine) const { return std::abs(sine) * size <= length; }
  /// Unit directions parallel or opposite.
  bool parallel(const Vec3& d1, const Vec3& d2) const {
    return negligible_angle(d1.cross(d2).norm());
  }
  /// Unit directions at a right angle.
  bool perpendicular(const Vec3& d1, const Vec3& d2) const { return negligible_angle(d1.dot(d2)); }
};

// ---- Fractions of the linear tolerance --------------------------------------------------------

/// Pcurves are fitted, and checked, to this fraction of the linear tolerance, so that the 3D
/// image of an edge's (u, v) curve stays well inside the band its 3D curve defines.
inline constexpr double kFitFraction = 1e-2;
inline double fit_tolerance(double linear) { return linear * kFitFraction; }

// ---- Parameter and (u, v) resolution ----------------------------------------------------------

/// Relative resolution of a curve parameter: parameters of one curve closer than
/// kParamRelative · max(1, scale) (scale: the span of the edge, or the parameter itself) name
/// one point — an edge is not split there, a hit there is at the end. For the unit-speed and
/// angular parameters of the engine's curves this is far below the linear tolerance
/// (1e-9 rad on a radius of 100 is 1e-7).
inline constexpr double kParamRelative = 1e-9;
inline double param_slack(double scale) { return kParamRelative * std::max(1.0, scale); }

/// Relative resolution of a face's parameter plane: the margin, relative to max(1, size of the
/// face's (u, v) domain), within which a point counts as on the sampled boundary polygon of a
/// face (and by which parameter boxes are padded).
inline constexpr double kUvRelative = 1e-9;
inline double uv_slack(double domain_size) { return kUvRelative * std::max(1.0, domain_size); }
/// Pcurve crossings with a face boundary are accepted within this many uv slacks.
inline constexpr double kCrossingUvSlacks = 10.0;
/// A section piece counts as inside a face when its middle lies this many uv slacks inside
/// the face's sampled boundary (closer is ambiguous: the piece runs along the boundary).
inline constexpr double kInsideUvSlacks = 10;
/// Ends of uses at one vertex are one node of a face's arrangement when their (u, v) are this
/// close relative to max(1, domain size) (a seam vertex gives two nodes, a period apart).
inline constexpr double kNodeUvRelative = 1e-7;

/// Point-in-face of the classifier (FaceQuery): the band around the boundary loops, relative
/// to the domain's size and position, within which a parameter point is OnBoundary. Tiny: the
/// chords' bulge bounds are rigorous, and the side is decided exactly outside the band.
inline constexpr double kFaceQueryUvRelative = 1e-12;

/// A face polygon's chord of a curved pcurve counts as bulging by this many times the largest
/// distance seen at three points of its arc (the band where a point is checked against the
/// arc itself).
inline constexpr double kArcBulgeSafety = 2.0;

/// Bounding volumes computed in floating point (face boxes, a torus' bounding sphere) are
/// grown by this relative amount so that rounding never lets a ray miss what it touches.
inline constexpr double kBoundsPadRelative = 1e-9;

/// A touching pair of ray–surface roots comes back as one root up to about √ε times the
/// face's size from the contact: a tangent hit within this fraction of the face's size of the
/// face's boundary makes the ray ambiguous.
inline constexpr double kTouchingRelative = 1e-6;

// ---- Curves running along each other ----------------------------------------------------------

/// Two pcurves meeting with the sine of their angle below this are nearly tangent there: the
/// crossing is kept only if they do not run along each other (kAlongUvRelative).
inline constexpr double kPcurveTangentSine = 1e-7;
/// Two pcurves run along each other (a shared stretch of coincident faces' boundaries, not a
/// crossing) when points of one a short step (kAlongProbeStep of its span) away from the
/// meeting point lie within this fraction of the curve's (u, v) length of the other.
inline constexpr double kAlongUvRelative = 1e-6;
inline constexpr double kAlongProbeStep = 1e-3;
/// Crossings of one pair of pcurves closer than this (relative to each curve's parameter
/// span) are one crossing found twice.
inline constexpr double kCrossingMergeRelative = 1e-7;

/// Traced (marched) sections: their chords stay within max(kTracedSagTolerances · linear
/// tolerance, kTracedSagRelative · problem size) of the exact curve — the edge tolerance such
/// a polyline edge then carries (finer chains would only cost time).
inline constexpr double kTracedSagTolerances = 10.0;
inline constexpr double kTracedSagRelative = 1e-6;
inline double traced_sag(double linear, double size) {
  return std::max(kTracedSagTolerances * linear, kTracedSagRelative * size);
}

/// A traced section's crossing with a face boundary moves to where the boundary edge pierces
/// the other surface when that point is within this many of the section's tolerances (its
/// measured deviation) of the crossing found on the chords; farther, it is another crossing.
inline constexpr double kTracedSnapReach = 100.0;

/// A closed-form section's crossing with a boundary edge reuses a vertex of that edge this
/// many linear tolerances away when the vertex lies on the section within tolerance (a grazing
/// crossing found a few tolerances apart by the sections that end there).
inline constexpr double kReuseReach = 100.0;

// ---- Numerical constants (not tolerances) ------------------------------------------------------

/// Newton refinement of a pcurve crossing stops when the two points are this fraction of the
/// crossing tolerance apart, or when a step is this small relative to the parameters.
inline constexpr double kNewtonConvergedFraction = 1e-3;
inline constexpr double kNewtonStall = 1e-15;
/// A piece's interior points come from triangles of its outline sampled with this many
/// points per pcurve, then kInteriorRefine times as many, up to kInteriorSamplesMax, until
/// enough of them lie inside the piece's exact (arc) outline.
inline constexpr int kInteriorSamples = 16;
inline constexpr int kInteriorRefine = 4;
inline constexpr int kInteriorSamplesMax = 1024;
/// Newton steps allowed for the point where an edge pierces a surface.
inline constexpr int kPierceIterations = 30;
/// Pcurves are cut into this many chords to find crossing candidates, and a chord's box is
/// grown by this fraction of its length for the arc's bulge.
inline constexpr int kCrossingSamples = 96;
inline constexpr double kCrossingBoxGrowth = 0.05;

/// The direction in which a use leaves a node is the chord over this fraction of its
/// parameter span (a chord, not the tangent, so that tangent curves are told apart by their
/// curvature).
inline constexpr double kLeavingChordStep = 1e-4;

/// When choosing a full sphere's seam, a candidate direction must beat the best so far by this
/// much (a preference for the earlier candidate, not a tolerance).
inline constexpr double kSeamPreference = 1e-9;

}  // namespace csgtile::kernel::detail
