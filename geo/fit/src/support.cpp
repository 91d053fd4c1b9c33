// Rule 4 of issue #18: every fitted primitive must be supported by its points (fit_internal.h).

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <vector>

#include "fit_internal.h"

namespace csgtile::fit::detail {

using kernel::PrimitiveSpec;
using kernel::PrimitiveType;
using kernel::Vec3;

// Empty when the primitive is supported, else the reason (counted in the fit's rejections):
//  - a curved primitive (cylinder, cone, sphere, torus, revolution) whose inliers cover less
//    than min_curved_coverage of its surface (the 20 m sphere over 49 points of a roof);
//  - any primitive reaching beyond the points of its region by more than max_overreach of
//    the region's extent (at least three connectivity cells) — above, beside, or below both
//    the region and the terrain under and around it;
//  - with a terrain grid, a flat slab (a box or an unclipped extrusion less than half a metre
//    high and at least min_building_width wide) whose top stays below min_building_height
//    over the terrain under it: raised ground the ground filter left (a quay, a street above
//    a canal), no building (a beam lying low is narrower).
std::string unsupported(const PrimitiveSpec& spec, const kernel::BoundingBox& box, double coverage,
                        const kernel::BoundingBox& region, double cell, const PrimitiveOptions& o) {
  const bool curved = spec.type != PrimitiveType::Box && spec.type != PrimitiveType::Extrusion;
  if (curved && coverage < o.min_curved_coverage) {
    char text[160];
    std::snprintf(text, sizeof text,
                  "unsupported: its points cover %.2g of its surface (min_curved_coverage %.2g)",
                  coverage, o.min_curved_coverage);
    return text;
  }
  if (region.empty() || box.empty()) return {};
  if (o.ground != nullptr && !curved && spec.clips.empty() && box.size().z() < 0.5 &&
      std::min(box.size().x(), box.size().y()) >= o.min_building_width) {
    const Vec3 c = 0.5 * (box.min + box.max);
    const double reach = 0.5 * Vec3(box.size().x(), box.size().y(), 0.0).norm();
    const double terrain = o.ground->lowest_near(c.x(), c.y(), reach);
    if (std::isfinite(terrain) && box.max.z() - terrain < o.min_building_height) {
      char text[160];
      std::snprintf(text, sizeof text,
                    "a slab %.2g thick %.2g over the terrain: raised ground, no building",
                    box.size().z(), box.max.z() - terrain);
      return text;
    }
  }
  const Vec3 extent = region.size();
  const double margin = std::max(3.0 * cell, o.max_overreach * extent.maxCoeff());
  double floor = region.min.z();
  if (o.ground != nullptr) {
    // The terrain around the region (a part in the middle of a large building sees none of
    // its own: the roof hides it).
    const Vec3 c = 0.5 * (region.min + region.max);
    const double reach = 0.5 * Vec3(extent.x(), extent.y(), 0.0).norm() + margin;
    const double low = o.ground->lowest_near(c.x(), c.y(), reach);
    if (std::isfinite(low)) floor = std::min(floor, low);
  }
  const double beyond = std::max({region.min.x() - box.min.x(), box.max.x() - region.max.x(),
                                  region.min.y() - box.min.y(), box.max.y() - region.max.y(),
                                  floor - box.min.z(), box.max.z() - region.max.z()});
  if (beyond > margin) {
    char text[160];
    std::snprintf(text, sizeof text,
                  "unsupported: reaches %.3g beyond the points of its region (allowed %.3g)",
                  beyond, margin);
    return text;
  }
  return {};
}

std::string flat_strips(const PrimitiveSpec& spec, std::span<const Vec3> points,
                        std::span<const std::uint32_t> members, double sigma, double cell) {
  const bool cone = spec.type == PrimitiveType::Cone;
  if ((!cone && spec.type != PrimitiveType::Cylinder) || members.size() < 8 || !(spec.height > 0.0))
    return {};
  const kernel::Location& at = spec.placement;
  const Eigen::Matrix3d& r = at.rotation();
  const double scale = at.scale();
  const double r1 = spec.radius, r2 = cone ? spec.radius2 : spec.radius, h = spec.height;
  const double cos_half = std::cos(std::atan2(r2 - r1, h));
  struct Local {
    double angle;
    std::uint32_t index;
  };
  std::vector<Local> around;
  around.reserve(members.size());
  double rss = 0.0, mean_radius = 0.0;
  for (auto i : members) {
    const Vec3 q = r.transpose() * (points[i] - at.translation()) / scale;
    const double rz = r1 + (r2 - r1) * std::clamp(q.z() / h, 0.0, 1.0);
    const double d = (std::hypot(q.x(), q.y()) - rz) * cos_half * scale;
    rss += d * d;
    mean_radius += rz * scale;
    around.push_back({std::atan2(q.y(), q.x()), i});
  }
  const auto n = static_cast<double>(members.size());
  mean_radius /= n;
  // Pieces of the surface around its axis: points further apart than two cells along the
  // circle (at the mean radius) start a new piece; the first and last join across ±π.
  std::sort(around.begin(), around.end(),
            [](const Local& a, const Local& b) { return a.angle < b.angle; });
  const double gap = 2.0 * cell / std::max(mean_radius, 1e-12);
  std::vector<std::vector<std::uint32_t>> pieces(1);
  for (std::size_t k = 0; k < around.size(); ++k) {
    if (k > 0 && around[k].angle - around[k - 1].angle > gap) pieces.emplace_back();
    pieces.back().push_back(around[k].index);
  }
  if (around.front().angle + 2.0 * std::numbers::pi - around.back().angle <= gap) {
    if (pieces.size() == 1) return {};  // a whole ring: curved beyond doubt
    pieces.front().insert(pieces.front().end(), pieces.back().begin(), pieces.back().end());
    pieces.pop_back();
  }
  // Each piece as a plane: its least principal variance is its residual.
  const double floor = std::max(sigma, 1e-9 * mean_radius);
  const int plane = parameter_count(ShapeType::Plane);
  double planes = 0.0;
  for (const auto& piece : pieces) {
    const auto principal = principal_axes(points, piece);
    const double residual = principal ? std::max(0.0, principal->values(0)) : 0.0;
    planes += information_criterion(residual, static_cast<double>(piece.size()), floor, plane, n);
  }
  const double curved = information_criterion(
      rss, n, floor, parameter_count(cone ? ShapeType::Cone : ShapeType::Cylinder), n);
  if (planes > curved) return {};
  char text[200];
  std::snprintf(text, sizeof text,
                "unsupported: its points are %d flat piece(s), planes explain them as well "
                "(curvature unseen)",
                static_cast<int>(pieces.size()));
  return text;
}

}  // namespace csgtile::fit::detail
