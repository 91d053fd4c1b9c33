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
/// The polygon of some loops on `face`'s surface (e.g. one piece's outer loop while the face
/// is being split), arcs kept as in face_polygon.
FacePolygon face_polygon(const BModel& m, const BFace& face, const std::vector<BLoop>& loops);

/// A crossing of a curve a(t) with a curve b(s) in the (u, v) plane.
struct Crossing {
  double t, s;
};
/// What intersect_pcurves looks at of a curve over [t0, t1]: the box of its sampled points
/// and how far a crossing may lie outside it (the candidate boxes' growth, and for a line the
/// parameter slack of a near miss at an end). Two curves whose boxes stay apart by more than
/// both reaches and the tolerance have no crossing, so the call can be skipped (a cull that
/// gives exactly the same answers). Two lines are never culled (their crossing comes from the
/// lines' intersection, whatever the boxes; the call is cheap).
struct CrossingBox {
  Vec2 min, max;
  double reach = 0;
  bool line = false;
};
CrossingBox crossing_box(const Curve2d& c, double t0, double t1);
/// The same from the curve's crossing_points (sampled once for many calls).
CrossingBox crossing_box(const Curve2d& c, double t0, double t1, const std::vector<Vec2>& points);
/// The points intersect_pcurves samples a curve at over [t0, t1] (polylines at least once per
/// segment), endpoints included.
std::vector<Vec2> crossing_points(const Curve2d& c, double t0, double t1);
/// Whether intersect_pcurves(a, b shifted by `shift_b`, tolerance) certainly finds nothing.
/// Conservative: boxes are padded for the rounding of a shifted copy's points.
bool crossing_boxes_apart(const CrossingBox& a, const CrossingBox& b, const Vec2& shift_b,
                          double tolerance);

/// Transversal or touching intersections of a(t), t ∈ [t0, t1] and b(s), s ∈ [s0, s1]:
/// candidates from sampled polylines, refined by Newton's method, deduplicated.
std::vector<Crossing> intersect_pcurves(const Curve2d& a, double t0, double t1, const Curve2d& b,
                                        double s0, double s1, double tolerance);
/// The same with a's samples given (`a_points` = crossing_points(a, t0, t1)): a curve crossed
/// with many others is sampled once.
std::vector<Crossing> intersect_pcurves(const Curve2d& a, double t0, double t1,
                                        const std::vector<Vec2>& a_points, const Curve2d& b,
                                        double s0, double s1, double tolerance);

}  // namespace csgtile::kernel::detail
