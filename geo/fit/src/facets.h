#pragma once
// Exact planar facets inside a curved candidate (the RANSAC's type selection by evidence, on
// exact clouds): the faces of a polygonal prism or pyramid (a hexagonal nut, an octagonal
// flange) lie within the inlier band of the cylinder or cone around them, but each face is a
// plane its points fit to rounding, which no patch of a true curved surface wider than a row
// of points does.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "csgtile/fit/fit.h"

namespace csgtile::fit::detail {

/// A plane and the points of `inliers` on it (ascending).
struct Facet {
  Surface plane;
  std::vector<std::uint32_t> points;
};

/// The largest exact planar facet among `inliers`: the points within `floor` of a plane whose
/// normals lie within acos(cos_alpha) of its normal (`has_normal[i]` says whether normals[i]
/// is one), the plane seeded by the point and normal of up to `max_seeds` inliers with
/// normals (an even stride: deterministic) and refitted to its points by least squares.
/// A facet must hold `min_points` points and be a patch, not a row of points: its points'
/// smaller spread across the plane (standard deviation) at least `min_spread`. nullopt when
/// no facet qualifies.
std::optional<Facet> largest_exact_facet(std::span<const kernel::Vec3> points,
                                         std::span<const kernel::Vec3> normals,
                                         std::span<const char> has_normal,
                                         std::span<const std::uint32_t> inliers, double floor,
                                         double cos_alpha, std::size_t min_points,
                                         double min_spread, std::size_t max_seeds = 48);

}  // namespace csgtile::fit::detail
