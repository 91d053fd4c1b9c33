#pragma once
// Triangulation of a polygon with holes in a plane (a face's (u, v) parameter plane): ear
// clipping after bridging each hole to the outer boundary.

#include <array>
#include <cstdint>
#include <vector>

#include "csgtile/kernel/location.h"

namespace csgtile::kernel::detail {

struct PolygonTriangulation {
  /// Counter-clockwise triangles; indices into the loops' points concatenated in order
  /// (loop 0 first). Every input point is used unless it repeats its predecessor.
  std::vector<std::array<std::uint32_t, 3>> triangles;
  /// False when part of the polygon could not be covered (it was degenerate: zero area or
  /// self-overlapping), so the triangles do not match the boundary.
  bool complete = true;
};

/// `loops[0]` is the outer boundary, the others holes; orientations may be either way (the
/// outer loop is taken counter-clockwise, holes clockwise). Points of a loop are its
/// vertices in order, without repeating the first at the end. The triangles use only the
/// given points (no Steiner points) and none has zero area. O(n²) for n points in practice
/// (O(n³) worst case on adversarial concave input).
PolygonTriangulation triangulate_polygon(const std::vector<std::vector<Vec2>>& loops);

}  // namespace csgtile::kernel::detail
