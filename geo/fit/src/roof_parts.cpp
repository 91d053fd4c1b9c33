// Roof parts seen from the air (issue #18 item 3): a tilted roof plane that no pitched-roof
// extrusion took becomes the linear extrusion of its points' outline, from the terrain under
// it up past the roof, cut by the half-space under its plane (a clipped primitive). The
// assembly fuses the parts of a building exactly. Hip roofs, L-shaped and irregular roofs,
// dormers are parts; a plane the pitched extrusions (pitched.cpp, which run first: a shed, a
// gable) took is not, nor a remnant most of whose points another primitive explains.

#include <algorithm>
#include <cmath>
#include <numbers>

#include "fit_internal.h"
#include "plane2d.h"

namespace csgtile::fit::detail {

using kernel::Vec2;

std::vector<Proposal> propose_roof_parts(const ProposalInput& in,
                                         std::vector<Rejection>& rejected) {
  std::vector<Proposal> out;
  const PrimitiveOptions& o = *in.options;
  if (o.ground == nullptr || !o.roof_parts) return out;
  const auto& shapes = in.shapes->shapes;
  const double cos_flat = std::cos(o.angle_tolerance_deg * std::numbers::pi / 180.0);
  const double cos_wall = std::cos(75.0 * std::numbers::pi / 180.0);  // steeper: a wall
  const double tight = 2.0 * in.ransac->epsilon;
  std::vector<int> roofs;
  for (std::size_t s = 0; s < shapes.size(); ++s) {
    const double nz = std::abs(shapes[s].surface.axis.z());
    if (shapes[s].surface.type == ShapeType::Plane && !(*in.absorbed)[s] && nz < cos_flat &&
        nz > cos_wall) {
      roofs.push_back(static_cast<int>(s));
    }
  }
  std::stable_sort(roofs.begin(), roofs.end(), [&](int a, int b) {
    return shapes[static_cast<std::size_t>(a)].inliers.size() >
           shapes[static_cast<std::size_t>(b)].inliers.size();
  });
  std::vector<char> claimed = *in.used;  // proposals share no point
  for (int roof : roofs) {
    const std::string what = "roof part from plane " + std::to_string(roof);
    const Surface& plane = shapes[static_cast<std::size_t>(roof)].surface;
    const Vec3 n = plane.axis.z() > 0.0 ? plane.axis : Vec3(-plane.axis);
    const double d = n.dot(plane.point);
    std::vector<std::uint32_t> pts;
    std::vector<Vec2> flat;
    for (auto i : shapes[static_cast<std::size_t>(roof)].inliers) {
      if (claimed[i]) continue;
      pts.push_back(i);
      flat.emplace_back(in.points[i].x(), in.points[i].y());
    }
    if (static_cast<long long>(pts.size()) < in.ransac->min_points) continue;
    // A plane most of whose points another primitive explains is a remnant of that one.
    if (2 * pts.size() < shapes[static_cast<std::size_t>(roof)].inliers.size()) continue;
    std::string why;
    const auto outline = roof_outline(
        in, flat, [&](const Vec3& p) { return n.dot(p) > d + tight; }, why);
    if (!outline) {
      if (!why.empty()) rejected.push_back({what, why, static_cast<long long>(pts.size())});
      continue;
    }
    const Vec2 u = outline->u, v = outline->v;
    const OutlineGround under = outline_ground(*outline, *o.ground);
    const double g = under.ground;
    // The roof's height over the outline's corners (a plane: its extremes are there).
    double low = INFINITY, high = -INFINITY;
    for (const auto& p : under.footprint) {
      const double z = (d - n.x() * p.x() - n.y() * p.y()) / n.z();
      low = std::min(low, z);
      high = std::max(high, z);
    }
    if (!std::isfinite(g) || high - g < o.min_building_height ||
        low - g < 0.5 * o.min_building_height) {
      rejected.push_back(
          {what, "its eaves are not above the terrain", static_cast<long long>(pts.size())});
      continue;
    }
    auto spec = outline_extrusion(*outline, under, high - g + 1.0);  // up past the roof
    if (!spec) continue;
    Proposal p;
    p.spec = std::move(*spec);
    const kernel::Location loc = p.spec.placement;
    // The plane in the local frame: n·(R x + t) <= d.
    const Vec3 nl = loc.rotation().transpose() * n;
    p.spec.clips.push_back(Eigen::Vector4d(nl.x(), nl.y(), nl.z(), d - n.dot(loc.translation())));
    // Members: unclaimed points over the outline (within a cell of it) and under the roof;
    // the outline's box in its frame first, so that the polygon tests meet only its points.
    double a0 = INFINITY, a1 = -INFINITY, b0 = INFINITY, b1 = -INFINITY;
    for (const auto& q : outline->profile) {
      a0 = std::min(a0, q.x() - outline->cell);
      a1 = std::max(a1, q.x() + outline->cell);
      b0 = std::min(b0, q.y() - outline->cell);
      b1 = std::max(b1, q.y() + outline->cell);
    }
    for (std::uint32_t i = 0; i < in.points.size(); ++i) {
      if (claimed[i] || !in.points[i].allFinite()) continue;
      const Vec3& q3 = in.points[i];
      const Vec2 q(Vec2(q3.x(), q3.y()).dot(u), Vec2(q3.x(), q3.y()).dot(v));
      if (q.x() < a0 || q.x() > a1 || q.y() < b0 || q.y() > b1) continue;
      if (q3.z() < g - tight || n.dot(q3) > d + tight) continue;
      if (inside_polygon(q, outline->profile, outline->holes) ||
          boundary_distance(q, outline->profile, outline->holes) <= outline->cell) {
        p.members.push_back(i);
      }
    }
    if (static_cast<long long>(p.members.size()) < in.ransac->min_points) continue;
    for (auto i : p.members) claimed[i] = 1;
    const double mean_height = 0.5 * (low + high) - g;
    p.area = polygon_area(outline->profile, outline->holes) / n.z() +
             polygon_perimeter(outline->profile, outline->holes) * mean_height;
    p.shapes = {roof};
    p.what = what;
    out.push_back(std::move(p));
  }
  return out;
}

}  // namespace csgtile::fit::detail
