// Exact planar facets inside a curved candidate (facets.h).

#include "facets.h"

#include <algorithm>
#include <cmath>

#include "fit_internal.h"

namespace csgtile::fit::detail {

namespace {

// The points of `inliers` within `floor` of `plane` with a normal within the angle of its
// normal (ascending, as `inliers` is).
std::vector<std::uint32_t> on_plane(std::span<const Vec3> points, std::span<const Vec3> normals,
                                    std::span<const char> has_normal,
                                    std::span<const std::uint32_t> inliers, const Surface& plane,
                                    double floor, double cos_alpha) {
  std::vector<std::uint32_t> out;
  for (const auto i : inliers) {
    if (!has_normal[i] || std::abs(normals[i].dot(plane.axis)) < cos_alpha) continue;
    if (std::abs((points[i] - plane.point).dot(plane.axis)) <= floor) out.push_back(i);
  }
  return out;
}

}  // namespace

std::optional<Facet> largest_exact_facet(std::span<const Vec3> points,
                                         std::span<const Vec3> normals,
                                         std::span<const char> has_normal,
                                         std::span<const std::uint32_t> inliers, double floor,
                                         double cos_alpha, std::size_t min_points,
                                         double min_spread, std::size_t max_seeds) {
  std::vector<std::uint32_t> seeds;
  for (const auto i : inliers) {
    if (has_normal[i]) seeds.push_back(i);
  }
  if (seeds.empty() || inliers.size() < min_points) return std::nullopt;
  const std::size_t stride =
      std::max<std::size_t>(1, seeds.size() / std::max<std::size_t>(max_seeds, 1));
  std::optional<Facet> best;
  for (std::size_t k = 0; k < seeds.size(); k += stride) {
    Surface plane;
    plane.type = ShapeType::Plane;
    plane.point = points[seeds[k]];
    plane.axis = normals[seeds[k]];
    auto on = on_plane(points, normals, has_normal, inliers, plane, floor, cos_alpha);
    if (on.size() < min_points || (best && on.size() <= best->points.size())) continue;
    // Refitted to its points (a seed's normal is an estimate), then taken again.
    const auto refit = fit_plane(points, on);
    if (!refit) continue;
    auto again = on_plane(points, normals, has_normal, inliers, *refit, floor, cos_alpha);
    if (again.size() < min_points || (best && again.size() <= best->points.size())) continue;
    // A patch, not a row: the smaller of the points' two spreads within the plane (standard
    // deviation; the smallest is across it).
    const auto principal = principal_axes(points, again);
    if (!principal || std::sqrt(std::max(principal->values(1), 0.0) /
                                static_cast<double>(again.size())) < min_spread) {
      continue;
    }
    best = Facet{*refit, std::move(again)};
  }
  return best;
}

}  // namespace csgtile::fit::detail
