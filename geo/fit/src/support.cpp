// Rule 4 of issue #18: every fitted primitive must be supported by its points (fit_internal.h).

#include <algorithm>
#include <cmath>
#include <cstdio>

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

}  // namespace csgtile::fit::detail
