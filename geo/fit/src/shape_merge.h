#pragma once
// The RANSAC's last step for CAD-like clouds (RansacOptions::merge_same_surface): shapes of
// one type on one surface whose points come within a narrow gap of each other are one face
// the connectivity broke apart, and become one shape.

#include <cstdint>
#include <span>
#include <vector>

#include "csgtile/fit/fit.h"

namespace csgtile::fit::detail {

/// Gap allowed between two shapes' points, in units of the larger of their 90 % quantiles of
/// nearest-neighbour distance (RansacOptions::merge_same_surface).
inline constexpr double kMergeGapFactor = 1.9;

/// Merges, transitively, every two `shapes` of one type whose inliers lie on each other's
/// surface (95 % of them within `epsilon`; normals are not asked: at edges and on sparse
/// samplings they are the least reliable part of a point) and come within kMergeGapFactor × the
/// larger of the two shapes' 90 % quantiles of their own nearest-neighbour distances of each other.
/// A merged shape keeps the place (and number) of the first of its parts; its surface is refitted
/// to all its inliers when the refit keeps each of them within `epsilon`. `assignment` (per point:
/// index into shapes, -1 none) is renumbered to match. With `exact` > 0 (exact clouds: the
/// residual under which a point is on a surface), two shapes are one only when the surface
/// refitted to both fits them within the larger of `exact` and ten times their own RMS: a spot
/// face a few thousandths below its face is its own. Returns the number of merges.
std::size_t merge_same_surface(std::span<const kernel::Vec3> points,
                               std::vector<DetectedShape>& shapes, std::vector<int>& assignment,
                               double epsilon, double exact = 0.0);

}  // namespace csgtile::fit::detail
