// Domes seen from the air (fit_internal.h, propose_domes): a sphere whose points are the upper
// cap of a roof becomes the sphere cut at the cap's base and the drum under it. Only where the
// sphere describes the points better than a plane does — the Bayesian information criterion of
// each on the same points, residuals capped at 3 ε (a point farther is an outlier to either)
// — and where the cap is one: points all around its vertical axis and up to its top.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <optional>

#include "fit_internal.h"
#include "plane2d.h"
#include "primitive_builder.h"

namespace csgtile::fit::detail {

namespace {

// n·ln(RSS/n) + k·ln(n) of residuals capped at `cap`.
double information(const std::vector<double>& residuals, double cap, int parameters) {
  const double n = static_cast<double>(residuals.size());
  double rss = 0.0;
  for (double r : residuals) rss += std::min(r * r, cap * cap);
  rss = std::max(rss, 1e-12 * cap * cap * n);  // exact points
  return n * std::log(rss / n) + parameters * std::log(n);
}

// Distances of the points to their least-squares plane (none: the points' spread).
std::vector<double> plane_residuals(std::span<const Vec3> points,
                                    const std::vector<std::uint32_t>& members) {
  const std::optional<Surface> plane = fit_plane(points, members);
  std::vector<double> out;
  out.reserve(members.size());
  for (auto i : members) {
    out.push_back(plane ? std::abs(surface_distance(*plane, points[i])) : INFINITY);
  }
  return out;
}

std::string format(const char* text, double a, double b) {
  char buffer[200];
  std::snprintf(buffer, sizeof buffer, text, a, b);
  return buffer;
}

}  // namespace

void cut_dome(Proposal& dome, double base) {
  const double cz = dome.spec.placement.apply_point(Vec3::Zero()).z();
  const double r = dome.spec.radius;
  // Kept where z_local >= base - cz: (0, 0, -1)·p <= cz - base.
  dome.spec.clips = {Eigen::Vector4d(0.0, 0.0, -1.0, cz - base)};
  dome.area = 2.0 * std::numbers::pi * r * (cz + r - base);
}

CapBase cap_base(const Proposal& dome) {
  const double cz = dome.spec.placement.apply_point(Vec3::Zero()).z();
  const double r = dome.spec.radius, z = cz - dome.spec.clips[0].w();
  return {z, std::sqrt(std::max(r * r - (z - cz) * (z - cz), 0.0))};
}

std::optional<kernel::PrimitiveSpec> drum_spec(const Vec2& axis, double radius, double z0,
                                               double height) {
  kernel::PrimitiveSpec spec;
  spec.type = PrimitiveType::Cylinder;
  spec.radius = radius;
  spec.height = height;
  auto foot = placement(Eigen::Matrix3d::Identity(), Vec3(axis.x(), axis.y(), z0));
  if (!foot) return std::nullopt;
  spec.placement = *foot;
  return spec;
}

std::vector<Proposal> propose_domes(const ProposalInput& in, std::vector<Rejection>& rejected) {
  std::vector<Proposal> out;
  const PrimitiveOptions& o = *in.options;
  if (o.ground == nullptr) return out;
  const double eps = in.ransac->epsilon;
  // Points an earlier dome of this call claims (proposals are kept after the call).
  std::vector<char> claimed(*in.used);
  std::vector<Vec2> region_hull;  // the region's outline, found when first needed
  for (std::size_t s = 0; s < in.shapes->shapes.size(); ++s) {
    const DetectedShape& shape = in.shapes->shapes[s];
    if (shape.surface.type != ShapeType::Sphere || (*in.absorbed)[s]) continue;
    const std::string what = "sphere " + std::to_string(s);
    std::vector<std::uint32_t> members;
    for (auto i : shape.inliers) {
      if (!claimed[i]) members.push_back(i);
    }
    if (static_cast<long long>(members.size()) < in.ransac->min_points) continue;
    const Vec3 c = shape.surface.point;
    const double radius = shape.surface.radius;
    auto reject = [&](std::string why) {
      rejected.push_back(
          {what, "no dome: " + std::move(why), static_cast<long long>(members.size())});
    };
    // The cap: from its points' lowest (or the equator, when they reach below it: where a
    // wall under the equator meets the sphere within the inlier distance) to the sphere's top.
    // A sphere with more than a tenth of its points below its equator is a ball seen from the
    // side, no cap seen from above.
    std::vector<double> z;
    for (auto i : members) z.push_back(in.points[i].z());
    std::sort(z.begin(), z.end());
    const double top = c.z() + radius;
    const auto below =
        static_cast<double>(std::lower_bound(z.begin(), z.end(), c.z() - 2.0 * eps) - z.begin());
    if (below > 0.1 * static_cast<double>(z.size())) {
      reject(
          format("%.0f %% of its points lie below its equator (at most %.0f %%): a ball, no cap "
                 "seen from above",
                 100.0 * below / static_cast<double>(z.size()), 10.0));
      continue;
    }
    const double base = std::max(z.front(), c.z());
    const double height = top - base;
    if (z.back() < top - 0.25 * height) {
      reject(format("its points stop %.3g below its top (cap %.3g high)", top - z.back(), height));
      continue;
    }
    std::array<bool, 36> sector{};
    for (auto i : members) {
      const double phi = std::atan2(in.points[i].y() - c.y(), in.points[i].x() - c.x());
      sector[static_cast<std::size_t>(std::clamp(
          (phi + std::numbers::pi) / (2.0 * std::numbers::pi) * 36.0, 0.0, 35.0))] = true;
    }
    const double span = 10.0 * static_cast<double>(std::count(sector.begin(), sector.end(), true));
    if (span < 270.0) {
      reject(format("its points span %.3g degrees around its vertical axis (%.3g needed)", span,
                    270.0));
      continue;
    }
    // By evidence: the sphere against the plane through the same points.
    std::vector<double> on_sphere;
    for (auto i : members) on_sphere.push_back(std::abs((in.points[i] - c).norm() - radius));
    const double sphere_bic = information(on_sphere, 3.0 * eps, 4);
    const double plane_bic = information(plane_residuals(in.points, members), 3.0 * eps, 3);
    if (!(sphere_bic < plane_bic)) {
      reject(format("a plane describes its points as well (information %.4g against %.4g)",
                    plane_bic, sphere_bic));
      continue;
    }
    // The drum: a vertical cylinder of the cap's base radius from the terrain under it up to
    // the base, when the base stands above the terrain.
    const double dz = base - c.z();
    const double base_radius = std::sqrt(std::max(radius * radius - dz * dz, 0.0));
    std::vector<Vec2> circle;
    for (int k = 0; k < 16; ++k) {
      const double a = 2.0 * std::numbers::pi * k / 16.0;
      circle.emplace_back(c.x() + base_radius * std::cos(a), c.y() + base_radius * std::sin(a));
    }
    double ground = lowest_ground_under(*o.ground, circle);
    if (!std::isfinite(ground)) ground = o.ground->median_near(c.x(), c.y(), 2.0 * base_radius);
    if (!std::isfinite(ground)) {
      // A dome amid a larger roof: the terrain around the whole region, as its building's.
      if (region_hull.empty()) {
        std::vector<Vec2> flat;
        for (const Vec3& p : in.points) {
          if (p.allFinite()) flat.emplace_back(p.x(), p.y());
        }
        region_hull = convex_hull(std::move(flat));
      }
      ground = lowest_ground_under(*o.ground, region_hull);
    }
    if (!std::isfinite(ground)) {
      reject("no terrain under it");
      continue;
    }
    const double floor = std::max(base, ground);
    Proposal dome;
    dome.spec.type = PrimitiveType::Sphere;
    dome.spec.radius = radius;
    auto at = placement(Eigen::Matrix3d::Identity(), c);
    if (!at) continue;
    dome.spec.placement = *at;
    cut_dome(dome, floor);
    // Its points: the cap's, and every other point of the region it explains (within 3 ε of
    // the cap or inside it: the noise's tails), which no roof part is then made of.
    for (std::size_t i = 0; i < in.points.size(); ++i) {
      const Vec3& p = in.points[i];
      if (!claimed[i] && p.z() >= floor - 3.0 * eps && (p - c).norm() <= radius + 3.0 * eps) {
        dome.members.push_back(static_cast<std::uint32_t>(i));
        claimed[i] = 1;
      }
    }
    dome.shapes = {static_cast<int>(s)};
    dome.what = what + " (dome)";
    out.push_back(std::move(dome));
    if (base - ground < o.min_building_height * 0.5) continue;  // a dome on the ground
    Proposal drum;
    auto spec = drum_spec(Vec2(c.x(), c.y()), base_radius, ground, base - ground);
    if (!spec) continue;
    drum.spec = std::move(*spec);
    // Its points: its wall's where the scan saw them, and any inside it, the dome's aside.
    for (std::size_t i = 0; i < in.points.size(); ++i) {
      const Vec3& p = in.points[i];
      if (claimed[i] || p.z() < ground - 3.0 * eps || p.z() > base + 3.0 * eps) continue;
      if (std::hypot(p.x() - c.x(), p.y() - c.y()) <= base_radius + 3.0 * eps) {
        drum.members.push_back(static_cast<std::uint32_t>(i));
        claimed[i] = 1;
      }
    }
    drum.area = 2.0 * std::numbers::pi * base_radius * drum.spec.height;
    drum.carried = true;
    drum.what = what + " (drum)";
    out.push_back(std::move(drum));
  }
  return out;
}

}  // namespace csgtile::fit::detail
