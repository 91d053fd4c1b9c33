#pragma once
// Small exact-enough helpers on 2D polygons used by the builders to validate profiles.

#include <vector>

#include "csgtile/kernel/location.h"

namespace csgtile::kernel::detail {

/// Twice the signed area (positive: counter-clockwise).
double signed_area2(const std::vector<Vec2>& ring);

/// Removes consecutive duplicates (within `eps`, wrapping) and collinear middle points.
std::vector<Vec2> clean_ring(const std::vector<Vec2>& ring, double eps);

/// True when two non-adjacent edges of the ring touch or cross, or the ring revisits a point.
bool ring_self_intersects(const std::vector<Vec2>& ring);

/// True when segments of two rings touch or cross.
bool rings_intersect(const std::vector<Vec2>& a, const std::vector<Vec2>& b);

/// Even-odd point-in-polygon test (points on the boundary may go either way).
bool point_in_ring(const Vec2& p, const std::vector<Vec2>& ring);

}  // namespace csgtile::kernel::detail
