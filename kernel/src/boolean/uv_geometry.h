#pragma once
// (u, v)-plane helpers of the Boolean engine: sampled face boundaries, point-in-face, and
// intersections of pcurves.

#include <optional>
#include <vector>

#include "boolean/model.h"

namespace csgtile::kernel::detail {

/// Points along a use's pcurve from its start to its end (direction of the use), endpoints
/// included; lines give their two ends.
std::vector<Vec2> sample_use(const BModel& m, const BUse& use, int samples = 24);

/// A face's boundary loops sampled as polygons in (u, v).
struct FacePolygon {
  std::vector<std::vector<Vec2>> loops;
  /// The stretch of pcurve a polygon side is the chord of (side i of loop l runs from
  /// loops[l][i] to the next point), with a bound on how far the curve bulges from the chord
  /// (0 for straight pieces). Empty for polygons made of points only.
  struct Arc {
    Curve2dPtr curve;
    double t0 = 0, t1 = 0;  // walking direction t0 → t1 (either order)
    double bulge = 0;
  };
  std::vector<std::vector<Arc>> arcs;
  Vec2 min, max;
  double u_period = 0, v_period = 0;
  /// Even-odd inside test; nullopt when `uv` is within `margin` of the boundary. A point
  /// between a side and the arc it is the chord of (where the sampled polygon and the face
  /// disagree) is decided against the arc.
  std::optional<bool> inside(const Vec2& uv, double margin) const;
  /// The period shift (0 or ±k·period) that brings `uv` strictly inside, if any.
  std::optional<Vec2> shift_inside(const Vec2& uv, double margin) const;
  /// Distance from `uv` to the boundary polygon.
  double boundary_distance(const Vec2& uv) const;
};
FacePolygon face_polygon(const BModel& m, const BFace& face);

/// A crossing of a curve a(t) with a curve b(s) in the (u, v) plane.
struct Crossing {
  double t, s;
};
/// Transversal or touching intersections of a(t), t ∈ [t0, t1] and b(s), s ∈ [s0, s1]:
/// candidates from sampled polylines, refined by Newton's method, deduplicated.
std::vector<Crossing> intersect_pcurves(const Curve2d& a, double t0, double t1, const Curve2d& b,
                                        double s0, double s1, double tolerance);

}  // namespace csgtile::kernel::detail
