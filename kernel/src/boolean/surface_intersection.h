#pragma once
/// \file
/// Closed-form surface–surface intersection for the Boolean operation (DESIGN §3, issue 4):
/// plane, cylinder, cone, sphere and torus pairs whose section is made of lines, circles and
/// ellipses. Not API.
///
/// Parametrisation contract (the Boolean fits exact trig-linear pcurves
/// p(t) = c + cos t·a + sin t·b + t·d on each surface, so a section's parameter must be an
/// angle or a length that both surfaces' own parameters follow linearly or
/// trigonometrically):
///  - lines are LineCurve with t = arc length; on a cylinder or cone they are generatrices
///    C(t) = S(u0, t) (origin S(u0, 0), direction ∂S/∂v);
///  - a circle around the axis of a cylinder, cone, sphere or torus is the TrigCurve
///    C(t) = S(t, v0) of that surface (centre on its axis, a = ρ·X, b = ρ·Y in its frame);
///    when both surfaces turn about that axis, surface `a`'s frame is used;
///  - a plane through a torus' or sphere's axis gives the meridian circles C(t) = S(u0, t);
///  - an oblique plane section of a cylinder is the ellipse C(t) = S_cyl(t, v(t)), and each
///    ellipse of two equal cylinders with crossing axes is such a section of cylinder `a`.
/// A circle whose axis is no surface's own axis (two spheres whose frames do not point along
/// the centre line, a plane cutting a sphere obliquely to its frame) uses the plane's frame
/// when there is a plane, otherwise a frame built around the circle's axis.

#include <string>
#include <vector>

#include "csgtile/kernel/bounding_box.h"
#include "csgtile/kernel/curve.h"
#include "csgtile/kernel/curve2d.h"
#include "csgtile/kernel/surface.h"

namespace csgtile::kernel::detail {

/// One branch of an intersection, in world coordinates.
struct SectionCurve {
  /// LineCurve (t = arc length) or TrigCurve (t an angle).
  CurvePtr curve;
  /// Parameter range: [0, 2π] for closed curves; for lines the part inside the clip box
  /// grown by a margin (see intersect_surfaces).
  double first = 0.0, last = 0.0;
  /// A full closed curve.
  bool closed = false;
  /// The surfaces touch along the curve without crossing (their normals are parallel there).
  bool tangent = false;
  /// Traced sections (no closed form): `curve` is a PolylineCurve through points on both
  /// surfaces, these are its pcurves on a and b (vertex i at t = i), and `deviation` the
  /// largest distance of its chords and pcurve images from the exact curve. Null / 0 for
  /// closed-form sections, whose pcurves the Boolean fits exactly.
  Curve2dPtr pcurve_a, pcurve_b;
  double deviation = 0.0;
};

enum class SsiKind {
  /// `curves` holds the whole intersection inside the clip box; empty = no intersection
  /// (isolated contact points are not reported: the Boolean finds them by classification).
  Curves,
  /// The surfaces are the same geometry within tolerance (in either orientation).
  Coincident,
  /// No closed form here; `reason` names the pair and the configuration.
  Unsupported
};

struct SsiResult {
  SsiKind kind = SsiKind::Curves;
  std::vector<SectionCurve> curves;
  std::string reason;
};

/// Intersection of two surfaces given in world coordinates, restricted to `clip`.
///
/// `tolerance` (a world length, > 0) decides every geometric question: a point is on a
/// surface within it, two directions are parallel when they drift apart by less than it
/// over the size of the problem (the clip box diagonal, or the largest radius when that is
/// bigger), and a near-tangent section collapses to one `tangent` curve when the two would-be
/// branches stay within it of both surfaces. Lines are clipped to `clip` grown by 5 % of the
/// size plus the tolerance; closed curves are returned whole, or dropped when their exact
/// bounds miss that grown box. An empty `clip` gives no curves (coincidence is still
/// reported). Surfaces that miss the grown box entirely give no curves, even for pairs that
/// are otherwise Unsupported.
///
/// Closed forms: plane–plane; plane with
/// cylinder (lines, circle, ellipse), cone (plane through the apex: generatrices; plane ⊥
/// axis: circle), sphere, torus (plane ⊥ axis or through the axis); cylinder–cylinder with
/// parallel axes, or equal radii and crossing axes (two ellipses); sphere–sphere; every pair
/// of cylinder, cone, sphere, torus turning about one common axis (a sphere counts when its
/// centre is on the other's axis); and pairs proven disjoint by a distance bound. Every other
/// pair is traced by marching (marching.h) with chords within max(10·tolerance, 1e-6·size) of
/// the exact curve; SsiKind::Unsupported remains for what the tracer refuses (tangent
/// contacts, singular points of the intersection), with its reason.
/// Deterministic; thread-safe (no shared state).
SsiResult intersect_surfaces(const Surface& a, const Surface& b, const BoundingBox& clip,
                             double tolerance);

}  // namespace csgtile::kernel::detail
