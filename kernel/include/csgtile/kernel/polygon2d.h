#pragma once
/// \file
/// Rings and polygons in the plane: the one home of their area, point-in-ring, distance,
/// simplification and validity helpers, for the kernel's builders and geo's fitting.
///
/// A ring is a closed polygon given as its vertices without a repeated closing vertex;
/// counter-clockwise rings have positive area. A polygon is an outer ring and its holes.
/// Results depend on these to the last bit: keep the order of every sum and comparison.

#include <array>
#include <cstddef>
#include <vector>

#include "csgtile/kernel/location.h"

namespace csgtile::kernel {

/// Signed area of a ring (shoelace): positive counter-clockwise.
double ring_area(const std::vector<Vec2>& ring);

/// Whether `p` lies inside the ring (even-odd rule, either orientation; points on the boundary
/// may go either way).
bool inside_ring(const Vec2& p, const std::vector<Vec2>& ring);

/// Whether `p` lies inside `outer` and in none of the `holes`.
bool inside_polygon(const Vec2& p, const std::vector<Vec2>& outer,
                    const std::vector<std::vector<Vec2>>& holes);

/// Distance from `p` to the segment a–b (to `a` when the segment has no length).
double segment_distance(const Vec2& p, const Vec2& a, const Vec2& b);

/// Distance from `p` to the nearest edge of `outer` or of one of the `holes` (infinity when
/// all rings are empty).
double boundary_distance(const Vec2& p, const std::vector<Vec2>& outer,
                         const std::vector<std::vector<Vec2>>& holes);

/// Total edge length of `outer` and its `holes`.
double polygon_perimeter(const std::vector<Vec2>& outer,
                         const std::vector<std::vector<Vec2>>& holes);

/// Area of `outer` less the areas of its `holes`, whatever the rings' orientations.
double polygon_area(const std::vector<Vec2>& outer, const std::vector<std::vector<Vec2>>& holes);

/// Douglas–Peucker on the chain points[i..j] (indices modulo points.size(), so a ring's arc
/// wraps round): marks in `keep` the vertices a simplification within `tol` keeps between
/// the ends (the ends themselves are the caller's).
void douglas_peucker(const std::vector<Vec2>& points, std::size_t i, std::size_t j, double tol,
                     std::vector<char>& keep);

/// Removes consecutive duplicates (within `eps`, wrapping) and collinear middle points
/// (relative test: cross product within 1e-14 of the edges' lengths); spikes are kept.
std::vector<Vec2> clean_ring(const std::vector<Vec2>& ring, double eps);

/// True when two non-adjacent edges of the ring touch or cross, two adjacent ones fold back
/// onto each other, or the ring revisits a point.
bool ring_self_intersects(const std::vector<Vec2>& ring);

/// True when segments of two rings touch or cross.
bool rings_intersect(const std::vector<Vec2>& a, const std::vector<Vec2>& b);

// ---- Exact rings on an integer grid (the roof partition's cell-edge rings) -----------------
// Nothing is rounded (coordinates below about 1e9: the doubled area stays within 64 bits).

/// A vertex of an integer grid.
using GridVertex = std::array<long long, 2>;

/// Sign (-1, 0, 1) of the turn a -> b -> c: positive counter-clockwise.
int grid_orientation(const GridVertex& a, const GridVertex& b, const GridVertex& c);

/// Whether the closed segments a-b and c-d meet anywhere but at one shared end (the same
/// segment twice, or two segments overlapping along a line from their shared end, conflict).
bool grid_segments_conflict(const GridVertex& a, const GridVertex& b, const GridVertex& c,
                            const GridVertex& d);

/// Twice the signed area of a ring (shoelace): positive counter-clockwise.
long long grid_ring_area2(const std::vector<GridVertex>& ring);

/// Whether the midpoint of a-b lies inside the ring (even-odd rule).
bool grid_midpoint_inside(const GridVertex& a, const GridVertex& b,
                          const std::vector<GridVertex>& ring);

}  // namespace csgtile::kernel
