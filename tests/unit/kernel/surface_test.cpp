// Surfaces (plane, cylinder, cone, sphere, torus, extrusion, revolution): evaluation against
// the formulas of surface.h, derivatives against finite differences, normals, point inversion
// against dense sampling, exact patch bounds against refined dense sampling, and
// transformed() under random similarities. Every random draw uses a fixed seed.

#include "csgtile/kernel/surface.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <functional>
#include <memory>
#include <numbers>
#include <random>

#include <string>
#include <tuple>
#include <vector>
#include "random_geometry.h"

namespace csgtile::kernel {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kTwoPi = 2.0 * std::numbers::pi;

using test::expect_near;
using test::random_frame;
using test::random_point;
using test::random_similarity;
using test::random_unit;

Vec3 radial(const Frame& f, double u) { return std::cos(u) * f.x + std::sin(u) * f.y; }

/// One surface under test with its valid parameter domain and how transformed() maps its
/// parameters (factor s = loc.scale() on u and/or v for length parameters).
struct Case {
  std::string name;
  SurfacePtr surface;
  ParamBox domain;
  bool u_periodic = false;
  bool v_periodic = false;
  bool u_is_length = false;
  bool v_is_length = false;
  /// Outward reference for closed quadrics: a point the normal must point away from.
  std::function<Vec3(double u, double v)> inside;
};

/// Two half-planes' frame used to place meridians: X0 ⊥ D.
struct AxisFrame {
  Vec3 origin, x, d;
};

std::vector<Case> make_cases() {
  std::mt19937 rng(7001);
  std::vector<Case> cases;
  {
    const Frame f = random_frame(rng);
    cases.push_back({"plane",
                     std::make_shared<PlaneSurface>(f),
                     {-2, 3, -1, 2.5},
                     false,
                     false,
                     true,
                     true,
                     nullptr});
  }
  {
    const Frame f = random_frame(rng);
    auto s = std::make_shared<CylinderSurface>(f, 1.5);
    cases.push_back(
        {"cylinder", s, {0, kTwoPi, -2, 3}, true, false, false, true, [f](double, double v) {
           return Vec3(f.origin + v * f.z);
         }});
  }
  for (double phi : {0.4, -0.3}) {
    const Frame f = random_frame(rng);
    auto s = std::make_shared<ConeSurface>(f, 1.0, phi);
    // Valid nappe: 1 + v·sin φ ≥ 0.
    const ParamBox domain = phi > 0 ? ParamBox{0, kTwoPi, -1 / std::sin(phi), 2.5}
                                    : ParamBox{0, kTwoPi, -2.5, -1 / std::sin(phi)};
    cases.push_back(
        {"cone" + std::to_string(phi), s, domain, true, false, false, true,
         [f, phi](double, double v) { return Vec3(f.origin + v * std::cos(phi) * f.z); }});
  }
  {
    const Frame f = random_frame(rng);
    auto s = std::make_shared<SphereSurface>(f, 2.0);
    cases.push_back({"sphere",
                     s,
                     {0, kTwoPi, -kPi / 2, kPi / 2},
                     true,
                     false,
                     false,
                     false,
                     [f](double, double) { return f.origin; }});
  }
  {
    const Frame f = random_frame(rng);
    auto s = std::make_shared<TorusSurface>(f, 3.0, 1.0);
    cases.push_back(
        {"torus", s, {0, kTwoPi, 0, kTwoPi}, true, true, false, false, [f](double u, double) {
           return Vec3(f.origin + 3.0 * radial(f, u));
         }});
  }
  // Extrusions of each basis kind, perpendicular and oblique.
  {
    const Frame f = random_frame(rng);
    auto basis = std::make_shared<CircleCurve>(f, 1.2);
    cases.push_back({"extrusion_circle",
                     std::make_shared<ExtrusionSurface>(basis, f.z * 2.0),
                     {0, kTwoPi, -1.5, 2},
                     true,
                     false,
                     false,
                     true,
                     nullptr});
  }
  {
    const Frame f = random_frame(rng);
    auto basis = std::make_shared<EllipseCurve>(f, 2.0, 0.7);
    const Vec3 d = (f.z + 0.8 * f.x - 0.5 * f.y).normalized();
    cases.push_back({"extrusion_ellipse_oblique",
                     std::make_shared<ExtrusionSurface>(basis, d),
                     {0, kTwoPi, -1.5, 2},
                     true,
                     false,
                     false,
                     true,
                     nullptr});
  }
  {
    const Frame f = random_frame(rng);
    auto basis = std::make_shared<CircleCurve>(f, 1.0);
    const Vec3 d = (f.z + 1.5 * f.y).normalized();
    cases.push_back({"extrusion_circle_oblique",
                     std::make_shared<ExtrusionSurface>(basis, d),
                     {0, kTwoPi, -1.5, 2},
                     true,
                     false,
                     false,
                     true,
                     nullptr});
  }
  {
    auto basis = std::make_shared<LineCurve>(random_point(rng, 3), random_unit(rng));
    cases.push_back({"extrusion_line",
                     std::make_shared<ExtrusionSurface>(basis, random_unit(rng)),
                     {-2, 3, -1.5, 2},
                     false,
                     false,
                     true,
                     true,
                     nullptr});
  }
  {
    // A simple planar zigzag extruded obliquely: the projection along D stays simple, so
    // the inversion's u is unique.
    const Frame f = random_frame(rng);
    std::vector<Vec3> points;
    for (int i = 0; i < 5; ++i) points.push_back(f.origin + i * f.x + (i % 2) * 1.3 * f.y);
    auto basis = std::make_shared<PolylineCurve>(points, 0.0);
    cases.push_back({"extrusion_polyline",
                     std::make_shared<ExtrusionSurface>(basis, f.z + 0.4 * f.x - 0.2 * f.y),
                     {0, 4, -1.5, 2},
                     false,
                     false,
                     false,
                     true,
                     nullptr});
  }
  // Revolutions: meridians in the half-plane of X0 around the axis (P, D).
  const auto axis_frame = [&rng] {
    const Frame f = random_frame(rng);
    return AxisFrame{f.origin, f.x, f.z};
  };
  {
    const AxisFrame a = axis_frame();
    const double phi = 0.3;
    auto meridian = std::make_shared<LineCurve>(a.origin + 1.0 * a.x,
                                                std::sin(phi) * a.x + std::cos(phi) * a.d);
    cases.push_back({"revolution_line",
                     std::make_shared<RevolutionSurface>(meridian, a.origin, a.d),
                     {0, kTwoPi, -1 / std::sin(phi), 2},
                     true,
                     false,
                     false,
                     true,
                     nullptr});
  }
  {
    // The patch lies beyond the point where the meridian line crosses the axis, on the side
    // opposite to the line's origin: inversion must use the mirrored half-plane.
    const AxisFrame a = axis_frame();
    const double phi = 0.5;
    auto meridian = std::make_shared<LineCurve>(a.origin + 1.0 * a.x,
                                                -std::sin(phi) * a.x + std::cos(phi) * a.d);
    const double crossing = 1 / std::sin(phi);
    cases.push_back({"revolution_line_far_side",
                     std::make_shared<RevolutionSurface>(meridian, a.origin, a.d),
                     {0, kTwoPi, crossing, crossing + 3},
                     true,
                     false,
                     false,
                     true,
                     nullptr});
  }
  {
    const AxisFrame a = axis_frame();
    Frame mf;
    mf.origin = a.origin + 3.0 * a.x;
    mf.x = a.x;
    mf.y = a.d;
    mf.z = a.x.cross(a.d);
    auto meridian = std::make_shared<CircleCurve>(mf, 1.0);
    cases.push_back({"revolution_circle",
                     std::make_shared<RevolutionSurface>(meridian, a.origin, a.d),
                     {0, kTwoPi, 0, kTwoPi},
                     true,
                     true,
                     false,
                     false,
                     nullptr});
  }
  {
    const AxisFrame a = axis_frame();
    Frame mf;
    mf.origin = a.origin;
    mf.x = a.x;
    mf.y = a.d;
    mf.z = a.x.cross(a.d);
    auto meridian = std::make_shared<CircleCurve>(mf, 2.0);
    // v is the meridian circle's angle: inversion returns it in [0, 2π).
    cases.push_back({"revolution_half_circle",
                     std::make_shared<RevolutionSurface>(meridian, a.origin, a.d),
                     {0, kTwoPi, -kPi / 2, kPi / 2},
                     true,
                     true,
                     false,
                     false,
                     nullptr});
  }
  {
    const AxisFrame a = axis_frame();
    const Frame mf = Frame::from_z(a.origin + 4.0 * a.x + a.d, a.x.cross(a.d), a.d);
    auto meridian = std::make_shared<EllipseCurve>(mf, 1.5, 0.8);
    cases.push_back({"revolution_ellipse",
                     std::make_shared<RevolutionSurface>(meridian, a.origin, a.d),
                     {0, kTwoPi, 0, kTwoPi},
                     true,
                     true,
                     false,
                     false,
                     nullptr});
  }
  {
    const AxisFrame a = axis_frame();
    std::vector<Vec3> points;
    for (const auto& [rho, z] :
         std::vector<std::pair<double, double>>{{0, -1}, {1, -1}, {1.5, 0}, {1, 1.2}, {0.2, 1.5}}) {
      points.push_back(a.origin + rho * a.x + z * a.d);
    }
    auto meridian = std::make_shared<PolylineCurve>(points, 0.0);
    cases.push_back({"revolution_polyline",
                     std::make_shared<RevolutionSurface>(meridian, a.origin, a.d),
                     {0, kTwoPi, 0, 4},
                     true,
                     false,
                     false,
                     false,
                     nullptr});
  }
  return cases;
}

/// Parameters on a grid strictly inside the domain (offset to avoid symmetric points).
std::vector<Vec2> interior_samples(const ParamBox& b, int n) {
  std::vector<Vec2> out;
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      out.emplace_back(b.u0 + (b.u1 - b.u0) * (i + 0.31) / n,
                       b.v0 + (b.v1 - b.v0) * (j + 0.57) / n);
    }
  }
  return out;
}

/// Compass search for the maximum of f over the box, from (u, v).
double refine_max_2d(const std::function<double(double, double)>& f, const ParamBox& box, double u,
                     double v, double step_u, double step_v) {
  const auto clamp_u = [&](double x) { return std::clamp(x, box.u0, box.u1); };
  const auto clamp_v = [&](double x) { return std::clamp(x, box.v0, box.v1); };
  double best = f(u, v);
  const int directions[8][2] = {{1, 0}, {-1, 0}, {0, 1},  {0, -1},
                                {1, 1}, {1, -1}, {-1, 1}, {-1, -1}};
  for (int iteration = 0; iteration < 20000 && (step_u > 1e-13 || step_v > 1e-13); ++iteration) {
    bool improved = false;
    for (const auto& d : directions) {
      const double cu = clamp_u(u + d[0] * step_u);
      const double cv = clamp_v(v + d[1] * step_v);
      const double value = f(cu, cv);
      if (value > best) {
        best = value;
        u = cu;
        v = cv;
        improved = true;
      }
    }
    if (!improved) {
      step_u *= 0.5;
      step_v *= 0.5;
    }
  }
  return best;
}

/// Maximum of f over the box: a dense grid, refined from the best few grid points.
double sampled_max_2d(const std::function<double(double, double)>& f, const ParamBox& box,
                      int n = 80) {
  std::vector<std::tuple<double, double, double>> values;
  for (int i = 0; i <= n; ++i) {
    for (int j = 0; j <= n; ++j) {
      const double u = box.u0 + (box.u1 - box.u0) * i / n;
      const double v = box.v0 + (box.v1 - box.v0) * j / n;
      values.emplace_back(f(u, v), u, v);
    }
  }
  std::sort(values.begin(), values.end(), std::greater<>());
  double best = std::get<0>(values.front());
  for (std::size_t k = 0; k < 6 && k < values.size(); ++k) {
    best = std::max(best, refine_max_2d(f, box, std::get<1>(values[k]), std::get<2>(values[k]),
                                        (box.u1 - box.u0) / n, (box.v1 - box.v0) / n));
  }
  return best;
}

// ---- evaluation ---------------------------------------------------------------------------

TEST(SurfaceEvaluationTest, QuadricsMatchTheDocumentedFormulas) {
  std::mt19937 rng(7101);
  const Frame f = random_frame(rng);
  const PlaneSurface plane(f);
  const CylinderSurface cylinder(f, 1.5);
  const ConeSurface cone(f, 1.2, 0.35);
  const SphereSurface sphere(f, 2.0);
  const TorusSurface torus(f, 3.0, 0.75);
  for (double u : {0.0, 0.7, 2.0, 4.5}) {
    for (double v : {-1.2, 0.0, 0.4, 1.5}) {
      const Vec3 e = radial(f, u);
      expect_near(plane.point(u, v), f.origin + u * f.x + v * f.y, 1e-14);
      expect_near(cylinder.point(u, v), f.origin + 1.5 * e + v * f.z, 1e-14);
      expect_near(cone.point(u, v),
                  f.origin + (1.2 + v * std::sin(0.35)) * e + v * std::cos(0.35) * f.z, 1e-14);
      expect_near(sphere.point(u, v), f.origin + 2.0 * std::cos(v) * e + 2.0 * std::sin(v) * f.z,
                  1e-14);
      expect_near(torus.point(u, v),
                  f.origin + (3.0 + 0.75 * std::cos(v)) * e + 0.75 * std::sin(v) * f.z, 1e-14);
    }
  }
  // The cone's apex is at v = −r / sin φ.
  expect_near(cone.point(1.0, -1.2 / std::sin(0.35)), cone.point(4.0, -1.2 / std::sin(0.35)),
              1e-14);
  EXPECT_EQ(plane.kind(), SurfaceKind::Plane);
  EXPECT_EQ(torus.kind(), SurfaceKind::Torus);
  EXPECT_DOUBLE_EQ(sphere.u_period(), kTwoPi);
  EXPECT_EQ(sphere.v_period(), 0.0);
  EXPECT_DOUBLE_EQ(torus.v_period(), kTwoPi);
  EXPECT_EQ(plane.u_period(), 0.0);
}

TEST(SurfaceEvaluationTest, ExtrusionOfACircleIsTheCylinder) {
  std::mt19937 rng(7102);
  const Frame f = random_frame(rng);
  const ExtrusionSurface extrusion(std::make_shared<CircleCurve>(f, 1.3), 4.0 * f.z);
  const CylinderSurface cylinder(f, 1.3);
  EXPECT_NEAR(extrusion.direction().norm(), 1.0, 1e-15);
  EXPECT_DOUBLE_EQ(extrusion.u_period(), kTwoPi);
  for (const Vec2& uv : interior_samples({0, kTwoPi, -2, 2}, 7)) {
    expect_near(extrusion.point(uv.x(), uv.y()), cylinder.point(uv.x(), uv.y()), 1e-14);
    expect_near(extrusion.normal(uv.x(), uv.y()), cylinder.normal(uv.x(), uv.y()), 1e-14);
  }
}

TEST(SurfaceEvaluationTest, RevolutionsOfCircleAndLineAreTorusAndCone) {
  std::mt19937 rng(7103);
  const Frame f = random_frame(rng);
  Frame meridian_frame;
  meridian_frame.origin = f.origin + 3.0 * f.x;
  meridian_frame.x = f.x;
  meridian_frame.y = f.z;
  meridian_frame.z = f.x.cross(f.z);
  const RevolutionSurface ring(std::make_shared<CircleCurve>(meridian_frame, 1.0), f.origin, f.z);
  const TorusSurface torus(f, 3.0, 1.0);
  const double phi = 0.45;
  const RevolutionSurface spun(
      std::make_shared<LineCurve>(f.origin + 0.8 * f.x, std::sin(phi) * f.x + std::cos(phi) * f.z),
      f.origin, f.z * 3.0);
  const ConeSurface cone(f, 0.8, phi);
  for (const Vec2& uv : interior_samples({0, kTwoPi, 0, kTwoPi}, 7)) {
    expect_near(ring.point(uv.x(), uv.y()), torus.point(uv.x(), uv.y()), 1e-13);
    expect_near(ring.normal(uv.x(), uv.y()), torus.normal(uv.x(), uv.y()), 1e-13);
    const double v = uv.y() - 1.0;
    expect_near(spun.point(uv.x(), v), cone.point(uv.x(), v), 1e-13);
    expect_near(spun.normal(uv.x(), v), cone.normal(uv.x(), v), 1e-13);
  }
}

// ---- derivatives and normals ----------------------------------------------------------------

TEST(SurfaceDerivativeTest, MatchCentralFiniteDifferences) {
  for (const Case& c : make_cases()) {
    SCOPED_TRACE(c.name);
    const Surface& s = *c.surface;
    constexpr double h = 1e-6;
    for (const Vec2& uv : interior_samples(c.domain, 6)) {
      const double u = uv.x();
      const double v = uv.y();
      const Vec3 fu = (s.point(u + h, v) - s.point(u - h, v)) / (2 * h);
      const Vec3 fv = (s.point(u, v + h) - s.point(u, v - h)) / (2 * h);
      expect_near(s.du(u, v), fu, 1e-7 * (1 + fu.norm()));
      expect_near(s.dv(u, v), fv, 1e-7 * (1 + fv.norm()));
    }
  }
}

TEST(SurfaceNormalTest, IsTheNormalisedCrossProduct) {
  for (const Case& c : make_cases()) {
    SCOPED_TRACE(c.name);
    const Surface& s = *c.surface;
    for (const Vec2& uv : interior_samples(c.domain, 6)) {
      const Vec3 n = s.normal(uv.x(), uv.y());
      EXPECT_NEAR(n.norm(), 1.0, 1e-14);
      expect_near(n, s.du(uv.x(), uv.y()).cross(s.dv(uv.x(), uv.y())).normalized(), 1e-12);
    }
  }
}

TEST(SurfaceNormalTest, PointsOutwardOnClosedQuadrics) {
  for (const Case& c : make_cases()) {
    if (!c.inside) continue;
    SCOPED_TRACE(c.name);
    for (const Vec2& uv : interior_samples(c.domain, 9)) {
      const Vec3 p = c.surface->point(uv.x(), uv.y());
      EXPECT_GT(c.surface->normal(uv.x(), uv.y()).dot(p - c.inside(uv.x(), uv.y())), 0.0);
    }
  }
}

TEST(SurfaceNormalTest, SingularPointsGiveTheLimitAlongV) {
  std::mt19937 rng(7201);
  const Frame f = random_frame(rng);
  const SphereSurface sphere(f, 2.0);
  const ConeSurface cone(f, 1.0, 0.5);
  const double apex = -1.0 / std::sin(0.5);
  for (double u : {0.0, 1.0, 3.0, 5.0}) {
    expect_near(sphere.normal(u, kPi / 2), f.z, 1e-15);
    expect_near(sphere.normal(u, -kPi / 2), -f.z, 1e-15);
    expect_near(sphere.normal(u, kPi / 2), sphere.normal(u, kPi / 2 - 1e-7), 1e-6);
    const Vec3 n = cone.normal(u, apex);
    EXPECT_NEAR(n.norm(), 1.0, 1e-15);
    expect_near(n, cone.normal(u, apex + 1e-6), 1e-12);
    expect_near(n, std::cos(0.5) * radial(f, u) - std::sin(0.5) * f.z, 1e-15);
  }
  // A revolved half circle closes at the poles like the sphere; a revolved segment starting
  // on the axis has a cone apex there.
  Frame mf;
  mf.origin = f.origin;
  mf.x = f.x;
  mf.y = f.z;
  mf.z = f.x.cross(f.z);
  const RevolutionSurface ball(std::make_shared<CircleCurve>(mf, 2.0), f.origin, f.z);
  const RevolutionSurface tip(
      std::make_shared<LineCurve>(f.origin, std::sin(0.5) * f.x + std::cos(0.5) * f.z), f.origin,
      f.z);
  for (double u : {0.0, 1.0, 3.0, 5.0}) {
    expect_near(ball.normal(u, kPi / 2), f.z, 1e-14);
    expect_near(ball.normal(u, -kPi / 2), -f.z, 1e-14);
    expect_near(tip.normal(u, 0.0), cone.normal(u, apex), 1e-14);
    EXPECT_TRUE(tip.normal(u, 0.0).allFinite());
  }
}

// ---- point inversion ----------------------------------------------------------------------

/// Whether parameters agree, modulo the periods.
double parameter_gap(double a, double b, bool periodic) {
  if (!periodic) return std::abs(a - b);
  const double d = std::remainder(a - b, kTwoPi);
  return std::abs(d);
}

TEST(SurfaceClosestTest, RoundTripsPointsOnTheSurface) {
  for (const Case& c : make_cases()) {
    SCOPED_TRACE(c.name);
    const Surface& s = *c.surface;
    for (const Vec2& uv : interior_samples(c.domain, 12)) {
      const Vec3 p = s.point(uv.x(), uv.y());
      const Vec2 found = s.closest_parameters(p);
      expect_near(s.point(found.x(), found.y()), p, 1e-11 * (1 + p.norm()));
      EXPECT_LE(parameter_gap(found.x(), uv.x(), c.u_periodic), 1e-9);
      EXPECT_LE(parameter_gap(found.y(), uv.y(), c.v_periodic), 1e-9);
      if (c.u_periodic) {
        EXPECT_GE(found.x(), 0.0);
        EXPECT_LT(found.x(), kTwoPi);
      }
      if (c.v_periodic && c.surface->v_period() > 0) {
        EXPECT_GE(found.y(), 0.0);
        EXPECT_LT(found.y(), kTwoPi);
      }
    }
  }
}

TEST(SurfaceClosestTest, OffSurfacePointsBeatDenseSampling) {
  std::mt19937 rng(7301);
  for (const Case& c : make_cases()) {
    SCOPED_TRACE(c.name);
    const Surface& s = *c.surface;
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    for (int i = 0; i < 25; ++i) {
      // Near a point of the patch so that the nearest point of an unbounded surface lies in
      // the sampled domain.
      const Vec3 base = s.point(c.domain.u0 + (c.domain.u1 - c.domain.u0) * unit(rng),
                                c.domain.v0 + (c.domain.v1 - c.domain.v0) * unit(rng));
      const Vec3 p = base + random_point(rng, 0.8);
      const Vec2 found = s.closest_parameters(p);
      const double distance = (s.point(found.x(), found.y()) - p).norm();
      const double best = -sampled_max_2d(
          [&](double u, double v) { return -(s.point(u, v) - p).norm(); }, c.domain, 40);
      EXPECT_LE(distance, best + 1e-9) << "p = " << p.transpose();
    }
  }
}

TEST(SurfaceClosestTest, AxisPointsInvertDeterministically) {
  const Frame f;
  EXPECT_EQ(CylinderSurface(f, 1.0).closest_parameters(Vec3(0, 0, 2.5)), Vec2(0, 2.5));
  EXPECT_EQ(SphereSurface(f, 1.0).closest_parameters(Vec3(0, 0, 2.5)), Vec2(0, kPi / 2));
  EXPECT_EQ(SphereSurface(f, 1.0).closest_parameters(Vec3(0, 0, -2.5)), Vec2(0, -kPi / 2));
  EXPECT_EQ(SphereSurface(f, 1.0).closest_parameters(Vec3(0, 0, 0)), Vec2(0, 0));
  const Vec2 t = TorusSurface(f, 3.0, 1.0).closest_parameters(Vec3(0, 0, 1.0));
  EXPECT_EQ(t.x(), 0.0);
  EXPECT_NEAR(t.y(), std::atan2(1.0, -3.0), 1e-15);
  // Beyond the apex of a cone the apex is nearest.
  const ConeSurface cone(f, 1.0, kPi / 4);
  const Vec2 a = cone.closest_parameters(Vec3(0, 0, -5.0));
  expect_near(cone.point(a.x(), a.y()), Vec3(0, 0, -1.0), 1e-14);
  EXPECT_EQ(a.x(), 0.0);
}

// ---- exact bounds -------------------------------------------------------------------------

/// A random sub-box of a case's domain; periodic parameters get ranges anywhere, also
/// crossing 2π or longer than a turn.
ParamBox random_box(std::mt19937& rng, const Case& c) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const auto interval = [&](double lo, double hi, bool periodic) {
    if (periodic) {
      const double start = -kTwoPi + 3 * kTwoPi * unit(rng);
      return std::pair{start, start + 0.05 + 1.2 * kTwoPi * unit(rng)};
    }
    double a = lo + (hi - lo) * unit(rng);
    double b = lo + (hi - lo) * unit(rng);
    if (b < a) std::swap(a, b);
    return std::pair{a, std::max(b, a + 1e-3)};
  };
  // The sphere's v and a cone's v stay in the valid domain even though both are "angles" or
  // unbounded in principle.
  const auto [u0, u1] = interval(c.domain.u0, c.domain.u1, c.u_periodic);
  const auto [v0, v1] = interval(c.domain.v0, c.domain.v1, c.v_periodic);
  return {u0, u1, v0, v1};
}

TEST(SurfaceBoundsTest, ExactAgainstRefinedDenseSampling) {
  std::mt19937 rng(7401);
  for (const Case& c : make_cases()) {
    SCOPED_TRACE(c.name);
    const Surface& s = *c.surface;
    for (int trial = 0; trial < 8; ++trial) {
      const ParamBox box = random_box(rng, c);
      const BoundingBox b = s.bounds(box);
      ASSERT_FALSE(b.empty());
      for (int i = 0; i < 3; ++i) {
        const double hi =
            sampled_max_2d([&](double u, double v) { return s.point(u, v)[i]; }, box, 40);
        const double lo =
            -sampled_max_2d([&](double u, double v) { return -s.point(u, v)[i]; }, box, 40);
        // Contains every sample (the refined extremes are samples too) and is tight.
        EXPECT_NEAR(b.max[i], hi, 1e-9)
            << "box " << box.u0 << " " << box.u1 << " " << box.v0 << " " << box.v1 << " axis " << i;
        EXPECT_NEAR(b.min[i], lo, 1e-9)
            << "box " << box.u0 << " " << box.u1 << " " << box.v0 << " " << box.v1 << " axis " << i;
        EXPECT_LE(hi, b.max[i] + 1e-12);
        EXPECT_GE(lo, b.min[i] - 1e-12);
      }
    }
  }
}

TEST(SurfaceBoundsTest, HandCheckedPatches) {
  const Frame f;
  // Upper hemisphere: the full disc in x, y and [0, r] in z.
  BoundingBox b = SphereSurface(f, 2.0).bounds({0, kTwoPi, 0, kPi / 2});
  expect_near(b.min, Vec3(-2, -2, 0), 1e-15);
  expect_near(b.max, Vec3(2, 2, 2), 1e-15);
  // A quarter of a torus, the outer half of the tube.
  b = TorusSurface(f, 3.0, 1.0).bounds({0, kPi / 2, -kPi / 2, kPi / 2});
  expect_near(b.min, Vec3(0, 0, -1), 1e-15);
  expect_near(b.max, Vec3(4, 4, 1), 1e-15);
  // Plane corners.
  b = PlaneSurface(f).bounds({-1, 2, 3, 4});
  expect_near(b.min, Vec3(-1, 3, 0), 0.0);
  expect_near(b.max, Vec3(2, 4, 0), 0.0);
  // Cone frustum from the apex (v = −1/sin φ) to v = 1 over a half turn.
  const double phi = kPi / 6;
  b = ConeSurface(f, 1.0, phi).bounds({0, kPi, -2.0, 1.0});
  expect_near(b.min, Vec3(-1.5, 0, -2 * std::cos(phi)), 1e-14);
  expect_near(b.max, Vec3(1.5, 1.5, std::cos(phi)), 1e-14);
}

// ---- transformed --------------------------------------------------------------------------

TEST(SurfaceTransformedTest, ConsistentUnderRandomSimilarities) {
  std::mt19937 rng(7501);
  for (const Case& c : make_cases()) {
    SCOPED_TRACE(c.name);
    const Surface& s = *c.surface;
    for (int trial = 0; trial < 3; ++trial) {
      const Location loc = random_similarity(rng);
      const SurfacePtr moved = s.transformed(loc);
      ASSERT_EQ(moved->kind(), s.kind());
      const double su = c.u_is_length ? loc.scale() : 1.0;
      const double sv = c.v_is_length ? loc.scale() : 1.0;
      const double tolerance = 1e-11 * (1.0 + loc.scale()) * (1.0 + loc.translation().norm());
      for (const Vec2& uv : interior_samples(c.domain, 5)) {
        const double u = uv.x();
        const double v = uv.y();
        const Vec3 expected = loc.apply_point(s.point(u, v));
        expect_near(moved->point(su * u, sv * v), expected, tolerance);
        expect_near(moved->normal(su * u, sv * v), loc.apply_direction(s.normal(u, v)), 1e-11);
        expect_near(moved->du(su * u, sv * v) * su, loc.apply_vector(s.du(u, v)), tolerance);
        expect_near(moved->dv(su * u, sv * v) * sv, loc.apply_vector(s.dv(u, v)), tolerance);
        // Inversion commutes with the similarity.
        const Vec2 found = moved->closest_parameters(expected);
        expect_near(moved->point(found.x(), found.y()), expected, tolerance);
      }
      const ParamBox box = random_box(rng, c);
      const BoundingBox b = moved->bounds({su * box.u0, su * box.u1, sv * box.v0, sv * box.v1});
      BoundingBox grown = b;
      grown.enlarge(tolerance);
      for (const Vec2& uv : interior_samples(box, 9)) {
        EXPECT_TRUE(grown.contains(loc.apply_point(s.point(uv.x(), uv.y()))));
      }
    }
  }
}

}  // namespace
}  // namespace csgtile::kernel
