#pragma once
// Triangulation of one face whose boundary is already discretised: the boundary points are
// mesh vertices shared with the neighbouring faces, so a face only adds interior points.

#include <array>
#include <cstdint>
#include <vector>

#include "csgtile/kernel/result.h"
#include "csgtile/kernel/surface.h"

namespace csgtile::kernel::detail {

using Triangle = std::array<std::uint32_t, 3>;

/// A boundary point of a face: its (u, v) on the face's surface and its mesh vertex.
struct BoundaryPoint {
  Vec2 uv;
  std::uint32_t id;
};

/// A face boundary: per wire (outer first, in the face body's own orientation: outer loop
/// counter-clockwise in (u, v), holes clockwise), per edge use in wire order, the use's
/// points from its start to its end, both included (so consecutive uses share a point).
using FaceLoops = std::vector<std::vector<std::vector<BoundaryPoint>>>;

/// The face's surface as placed in the model, and the error budget for its interior.
struct FaceGeometry {
  const Surface* surface = nullptr;  ///< in the face body's frame
  Location location;                 ///< the face's composed location
  double chordal = 0.0;              ///< world units
  double angular = 0.0;              ///< radians
  Vec3 point(const Vec2& uv) const { return location.apply_point(surface->point(uv.x(), uv.y())); }
};

/// Appends (a, b, c) unless two of its vertices are the same mesh vertex or it has zero area.
void add_triangle(const std::vector<Vec3>& vertices, std::vector<Triangle>& triangles,
                  std::uint32_t a, std::uint32_t b, std::uint32_t c);

/// Row method for faces whose domain is a (u, v) rectangle: one loop of axis-parallel edge
/// uses forming bottom (+u), right (+v), top (-u) and left (-v) sides, the left and right
/// sides sampled at the same v values. Rows run along u at those v values (bottom and top
/// rows are the boundary points), interior rows get uniform u samples for the face's budget,
/// and consecutive rows are zipped into strips; collapsed rows (poles, apexes) become fans.
/// Returns false, adding nothing, when the domain is not such a rectangle.
/// Error: InvalidArgument when a row would need more than kMaxSegments segments.
Result<bool> mesh_rectangular_face(const FaceGeometry& geometry, const FaceLoops& loops,
                                   std::vector<Vec3>& vertices, std::vector<Triangle>& triangles);

/// General method: triangulates the boundary polygon in the (u, v) plane (ear clipping with
/// hole bridging). Unless the surface is a plane it then makes the triangulation Delaunay
/// (in (u, v) scaled by the surface's speeds at the domain centre; v shrunk where the surface
/// is straight along v), inserts interior points on rows spaced for half the budget in each
/// direction, and refines interior edges (never boundary ones) by midpoint splits until the
/// chordal error at edge midpoints and triangle centres is within the budget (at most 32
/// passes). Error: DegenerateGeometry when the boundary cannot be triangulated.
Status mesh_general_face(const FaceGeometry& geometry, const FaceLoops& loops,
                         std::vector<Vec3>& vertices, std::vector<Triangle>& triangles);

}  // namespace csgtile::kernel::detail
