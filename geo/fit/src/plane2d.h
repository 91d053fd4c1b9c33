#pragma once
// Plane geometry shared by the fitting module's proposers (extrusion.cpp, roof.cpp,
// primitives.cpp): the convex hull, the smallest rectangle around a polygon, and the frame
// and placement of a fitted solid. Rings and polygons (closed vertex lists, no repeated
// closing vertex; counter-clockwise has positive area) are the kernel's (polygon2d.h).

#include <optional>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "csgtile/kernel/location.h"
#include "csgtile/kernel/polygon2d.h"

namespace csgtile::fit::detail {

using kernel::Vec2;
using kernel::Vec3;

// Rings and polygons: kernel/polygon2d.h.
using kernel::boundary_distance;
using kernel::douglas_peucker;
using kernel::inside_polygon;
using kernel::inside_ring;
using kernel::polygon_area;
using kernel::polygon_perimeter;
using kernel::ring_area;
using kernel::segment_distance;

/// z of the cross product a × b (positive when b turns left from a).
inline double cross2(const Vec2& a, const Vec2& b) { return a.x() * b.y() - a.y() * b.x(); }

/// z of (a − o) × (b − o): positive when o → a → b turns left.
inline double cross2(const Vec2& o, const Vec2& a, const Vec2& b) {
  return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
}

/// Convex hull (Andrew's monotone chain): counter-clockwise, no repeated or collinear point.
/// Fewer than 3 distinct points come back sorted (by x, then y) as they are.
std::vector<Vec2> convex_hull(std::vector<Vec2> points);

/// A rectangle with a side along the unit direction `dir`: [a0, a1] along `dir`, [b0, b1]
/// along across() (dir turned left).
struct OrientedRectangle {
  Vec2 dir;
  double a0 = 0.0, a1 = 0.0, b0 = 0.0, b1 = 0.0;
  Vec2 across() const { return {-dir.y(), dir.x()}; }
  /// Corners, counter-clockwise from (a0, b0).
  std::vector<Vec2> corners() const;
};

/// The smallest rectangle around `polygon` with a side along one of its edges: on a convex
/// hull, the smallest of all (rotating calipers, by brute force, O(n²)). An edge's rectangle
/// replaces the best so far only when smaller by more than `slack` (ties: the first edge).
/// nullopt when no edge has a length.
std::optional<OrientedRectangle> smallest_rectangle(const std::vector<Vec2>& polygon, double slack);

/// The frame of the smallest rectangle around the points' convex hull (u along one of its
/// sides, v = u turned left; u = x when the hull has no edge) and the points' extent in it:
/// a = p·u in [a0, a1], b = p·v in [b0, b1]. nullopt when the hull has fewer than 3 points.
struct PrincipalFrame {
  Vec2 u{1.0, 0.0}, v{0.0, 1.0};
  double a0 = 0.0, a1 = 0.0, b0 = 0.0, b1 = 0.0;
};
std::optional<PrincipalFrame> principal_frame(const std::vector<Vec2>& points);

/// Rotation whose columns are: x made orthogonal to z, z × x, and z (all unit, right-handed).
/// x only needs a component across z; its length does not matter but enters the rounding.
Eigen::Matrix3d frame_of(const Vec3& x, const Vec3& z);

/// The location with that rotation and origin; nullopt when the kernel refuses the matrix.
std::optional<kernel::Location> place(const Eigen::Matrix3d& rotation, const Vec3& origin);

/// The algebraic (Kåsa) least-squares circle x² + y² + D·x + E·y + F = 0 through the points
/// (normal equations, solved by LDLᵀ); nullopt when they fix no circle (collinear, too few).
struct Circle2 {
  Vec2 centre;
  double radius = 0.0;
};
std::optional<Circle2> fit_circle(const std::vector<Vec2>& points);

}  // namespace csgtile::fit::detail
