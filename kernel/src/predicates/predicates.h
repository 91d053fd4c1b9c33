#pragma once
/// \file
/// Exact geometric predicates on double coordinates (private to the kernel).
///
/// Every function returns the sign of a polynomial in its (double) arguments exactly as if it
/// were evaluated in real arithmetic: -1, 0 or +1. A floating-point evaluation is tried first
/// together with a rigorous bound on its rounding error (a static filter); only when the value
/// lies within that bound is the polynomial evaluated again exactly, as a floating-point
/// expansion (a sum of non-overlapping doubles built from error-free two-sums and fused-
/// multiply-add two-products). The answer does not depend on which path decided it.
///
/// Domain: finite inputs whose nonzero coordinates have magnitudes in [2^-250, 2^250]
/// (about 5e-76 … 2e75): no intermediate product then underflows or overflows, which is what
/// the error-free transformations need. Zero coordinates are always fine.
///
/// Conventions (all determinants of exact differences):
///  - orient2d(a, b, c) = sign det[b - a, c - a]: +1 when a, b, c turn counter-clockwise
///    (c left of the directed line a → b), -1 clockwise, 0 collinear.
///  - orient3d(a, b, c, d) = sign det[b - a, c - a, d - a] = sign ((b - a) × (c - a))·(d - a):
///    +1 when d lies on the side of the plane through a, b, c towards which the normal
///    (b - a) × (c - a) points (a, b, c counter-clockwise seen from d), 0 coplanar.
///
/// Thread-safe; no allocation except polygon_orientation's exact stage on long rings.

#include <cstdint>
#include <span>
#include <vector>

#include "csgtile/kernel/location.h"

namespace csgtile::kernel::predicates {

int orient2d(const Vec2& a, const Vec2& b, const Vec2& c);
int orient3d(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);

/// Side of the point p with respect to the oriented plane through `origin` with normal
/// `normal` (any length): sign (p - origin)·normal.
int orient_plane(const Vec3& p, const Vec3& origin, const Vec3& normal);

/// sign (u × v) = sign (u.x·v.y - u.y·v.x): +1 when v is counter-clockwise from u.
int cross_sign(const Vec2& u, const Vec2& v);
/// sign ((a1 - a0) × (b1 - b0)) with the differences taken exactly: 0 when the segments
/// a0a1 and b0b1 are parallel (or one is a point).
int cross_sign(const Vec2& a0, const Vec2& a1, const Vec2& b0, const Vec2& b1);
/// sign (u·v).
int dot_sign(const Vec2& u, const Vec2& v);
int dot_sign(const Vec3& u, const Vec3& v);

/// Sign of the signed area of the closed polygon `ring` (last point joined to the first):
/// +1 counter-clockwise, -1 clockwise, 0 for zero area (fewer than three points included).
int polygon_orientation(std::span<const Vec2> ring);

/// Whether p lies on the closed segment ab (a point when a == b).
bool on_segment(const Vec2& p, const Vec2& a, const Vec2& b);

/// How two closed segments a0a1 and b0b1 meet.
enum class SegmentRelation {
  Disjoint,  ///< no common point
  Cross,     ///< one common point, interior to both (a proper crossing)
  Touch,     ///< one common point that is an end of at least one segment
  Overlap,   ///< collinear, sharing more than a point
};
SegmentRelation classify_segments(const Vec2& a0, const Vec2& a1, const Vec2& b0, const Vec2& b1);

/// Whether the segment ab crosses the ray from q towards +x, with the half-open rule of the
/// even–odd test (an end exactly at q's height counts on the side of greater y only), so
/// that a ring's crossings have the parity of q's containment. Precondition for a
/// meaningful answer: q is not on the segment (check on_segment first).
bool crosses_ray(const Vec2& a, const Vec2& b, const Vec2& q);

/// Where a point lies with respect to polygons.
enum class PolygonLocation { Inside, Outside, OnBoundary };
/// Even–odd containment of q in the region bounded by `rings` (each closed: last point
/// joined to the first), decided exactly: OnBoundary only when q is exactly on an edge.
PolygonLocation locate_in_polygon(const Vec2& q, std::span<const std::vector<Vec2>> rings);

/// Sweeping clockwise from the direction `from` (exclusive) all the way round to `from`
/// itself (inclusive, last), whether the direction d1 is met strictly before d2. Directions
/// are nonzero vectors compared by angle only; equal angles are not "before" each other.
bool clockwise_before(const Vec2& from, const Vec2& d1, const Vec2& d2);

/// The primitive sign computations, for the counters (the helpers above count through them).
enum class PredicateKind { Orient2d, Orient3d, OrientPlane, Cross, Dot, PolygonOrientation };
inline constexpr int kPredicateKinds = 6;

/// Debug counters of the calling thread since its last reset: how many predicate calls were
/// made, and how many of them the floating-point filter could not decide (exact stage), in
/// total and per kind.
struct PredicateStats {
  std::uint64_t calls = 0;
  std::uint64_t exact = 0;
  std::uint64_t calls_by_kind[kPredicateKinds] = {};
  std::uint64_t exact_by_kind[kPredicateKinds] = {};
};
PredicateStats predicate_stats();
void reset_predicate_stats();

}  // namespace csgtile::kernel::predicates
