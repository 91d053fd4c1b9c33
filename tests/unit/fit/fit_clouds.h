#pragma once
// Small synthetic clouds with known answers for the fitting tests: points on one surface
// patch with Gaussian noise along the normal, drawn from a seeded generator with our own
// transforms (the standard distributions differ between libraries).

#include <cmath>
#include <cstdint>
#include <functional>
#include <numbers>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "csgtile/fit/fit.h"
#include "csgtile/kernel/location.h"

namespace csgtile::fit::testing {

using kernel::Vec3;

class Draw {
 public:
  explicit Draw(std::uint64_t seed) : engine_(seed) {}
  double uniform() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  double normal() {
    for (;;) {
      const double u = 2.0 * uniform() - 1.0, v = 2.0 * uniform() - 1.0;
      const double s = u * u + v * v;
      if (s > 0.0 && s < 1.0) return u * std::sqrt(-2.0 * std::log(s) / s);
    }
  }

 private:
  std::mt19937_64 engine_;
};

/// Two unit vectors orthogonal to `a` and to each other.
inline void basis(const Vec3& a, Vec3& e1, Vec3& e2) {
  const Vec3 helper = std::abs(a.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
  e1 = a.cross(helper).normalized();
  e2 = a.cross(e1);
}

/// A cloud: points with their true normals.
struct Cloud {
  std::vector<Vec3> points;
  std::vector<Vec3> normals;
  void add(const Vec3& p, const Vec3& n, double noise, Draw& d) {
    points.push_back(p + noise * d.normal() * n);
    normals.push_back(n);
  }
  void append(const Cloud& other) {
    points.insert(points.end(), other.points.begin(), other.points.end());
    normals.insert(normals.end(), other.normals.begin(), other.normals.end());
  }
};

/// Cylinder side: axis through `base` along unit `axis`, angles [a0, a1], heights [0, h].
inline Cloud cylinder_cloud(const Vec3& base, const Vec3& axis, double r, double h, double a0,
                            double a1, int n, double noise, std::uint64_t seed) {
  Draw d(seed);
  Vec3 e1, e2;
  basis(axis, e1, e2);
  Cloud c;
  for (int i = 0; i < n; ++i) {
    const double t = d.uniform(a0, a1), z = d.uniform(0.0, h);
    const Vec3 radial = std::cos(t) * e1 + std::sin(t) * e2;
    c.add(base + z * axis + r * radial, radial, noise, d);
  }
  return c;
}

/// Cone side: apex, unit axis into the cone, half-angle, distances [t0, t1] along the axis.
inline Cloud cone_cloud(const Vec3& apex, const Vec3& axis, double half_angle, double t0, double t1,
                        int n, double noise, std::uint64_t seed) {
  Draw d(seed);
  Vec3 e1, e2;
  basis(axis, e1, e2);
  Cloud c;
  for (int i = 0; i < n; ++i) {
    const double phi = d.uniform(0.0, 2.0 * std::numbers::pi);
    // Uniform over the area: t² uniform.
    const double t = std::sqrt(d.uniform(t0 * t0, t1 * t1));
    const Vec3 radial = std::cos(phi) * e1 + std::sin(phi) * e2;
    const Vec3 p = apex + t * axis + t * std::tan(half_angle) * radial;
    const Vec3 normal = (std::cos(half_angle) * radial - std::sin(half_angle) * axis).normalized();
    c.add(p, normal, noise, d);
  }
  return c;
}

/// Sphere points with z above centre.z + z_min (a scan from above sees a cap).
inline Cloud sphere_cloud(const Vec3& centre, double r, double z_min, int n, double noise,
                          std::uint64_t seed) {
  Draw d(seed);
  Cloud c;
  while (static_cast<int>(c.points.size()) < n) {
    Vec3 v(d.normal(), d.normal(), d.normal());
    v.normalize();
    if (r * v.z() < z_min) continue;
    c.add(centre + r * v, v, noise, d);
  }
  return c;
}

/// Torus surface: centre, unit axis, major R, minor r; uniform in both angles.
inline Cloud torus_cloud(const Vec3& centre, const Vec3& axis, double major, double minor, int n,
                         double noise, std::uint64_t seed) {
  Draw d(seed);
  Vec3 e1, e2;
  basis(axis, e1, e2);
  Cloud c;
  for (int i = 0; i < n; ++i) {
    const double u = d.uniform(0.0, 2.0 * std::numbers::pi);
    const double v = d.uniform(0.0, 2.0 * std::numbers::pi);
    const Vec3 radial = std::cos(u) * e1 + std::sin(u) * e2;
    const Vec3 normal = std::cos(v) * radial + std::sin(v) * axis;
    c.add(centre + major * radial + minor * normal, normal, noise, d);
  }
  return c;
}

/// A planar rectangle: corner, two edge vectors, spacing-driven count; normal = e1 × e2.
inline Cloud rectangle_cloud(const Vec3& corner, const Vec3& e1, const Vec3& e2, double spacing,
                             double noise, std::uint64_t seed) {
  Draw d(seed);
  const Vec3 n = e1.cross(e2).normalized();
  const int count = static_cast<int>(e1.norm() * e2.norm() / (spacing * spacing));
  Cloud c;
  for (int i = 0; i < count; ++i) {
    c.add(corner + d.uniform() * e1 + d.uniform() * e2, n, noise, d);
  }
  return c;
}

/// The walls of an axis-aligned rectangular building over [lo, hi] (x, y), from z = 0 up to
/// `height`: `count` points drawn uniformly along its perimeter (from lo, +x first, then +y,
/// -x, -y) and in z, each along its wall's outward normal with `noise`.
inline void add_rectangle_walls(Cloud& c, const kernel::Vec2& lo, const kernel::Vec2& hi,
                                double height, int count, double noise, Draw& d) {
  const double w = hi.x() - lo.x(), h = hi.y() - lo.y();
  for (int k = 0; k < count; ++k) {
    const double t = d.uniform(0.0, 2.0 * (w + h)), z = d.uniform(0.0, height);
    const auto [p, n] = t < w       ? std::pair{Vec3(lo.x() + t, lo.y(), z), Vec3(0, -1, 0)}
                        : t < w + h ? std::pair{Vec3(hi.x(), lo.y() + t - w, z), Vec3(1, 0, 0)}
                        : t < 2 * w + h
                            ? std::pair{Vec3(hi.x() - (t - w - h), hi.y(), z), Vec3(0, 1, 0)}
                            : std::pair{Vec3(lo.x(), hi.y() - (t - 2 * w - h), z), Vec3(-1, 0, 0)};
    c.add(p, n, noise, d);
  }
}

/// Angle in degrees between two lines (directions up to sign).
inline double line_angle_deg(const Vec3& a, const Vec3& b) {
  const double c = std::min(1.0, std::abs(a.normalized().dot(b.normalized())));
  return std::acos(c) * 180.0 / std::numbers::pi;
}

/// Distance from point p to the line through q along unit a.
inline double line_distance(const Vec3& p, const Vec3& q, const Vec3& a) {
  const Vec3 v = p - q;
  return (v - v.dot(a) * a).norm();
}

/// Flat terrain at z = 0 over [-20, 60]² (cells of 2 m), each cell's lowest point 3 cm below
/// it: the ground grid of the airborne tests.
inline GroundGrid flat_ground() {
  GroundGrid g;
  g.x0 = g.y0 = -20.0;
  g.cell = 2.0;
  g.nx = g.ny = 40;
  g.z.assign(1600, -0.03);
  g.mean.assign(1600, 0.0);
  return g;
}

/// How an airborne region is fitted in the roof tests: the RANSAC's inlier distance and seed
/// (at least 40 points a shape), extrusions on or off, and the building's footprint if any.
struct AirborneFit {
  double epsilon = 0.02;  ///< the fit's default, as on the real tiles
  std::uint64_t seed = 3;
  bool extrusions = true;
  const std::vector<geo::FootprintPolygon>* footprint = nullptr;
};

/// A region seen from the air: its RANSAC shapes made primitives standing on `ground`.
inline FittedPrimitives fit_airborne(const Cloud& c, const GroundGrid& ground,
                                     const AirborneFit& how = {}) {
  RansacOptions o;
  o.epsilon = how.epsilon;
  o.min_points = 40;
  o.seed = how.seed;
  auto shapes = detect_shapes(c.points, c.normals, o);
  EXPECT_TRUE(shapes.ok());
  if (!shapes.ok()) return {};
  PrimitiveOptions options;
  options.ground = &ground;
  options.extrusions = how.extrusions;
  options.footprint = how.footprint;
  return primitives_from_shapes(c.points, c.normals, shapes.value(), options, o, 0);
}

}  // namespace csgtile::fit::testing
