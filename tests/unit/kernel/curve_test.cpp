// Curves (line, circle, ellipse, polyline), 2D pcurves and frames: evaluation against the
// formulas of curve.h, derivatives against finite differences, point inversion against dense
// sampling, exact support/bounds, lengths and transformed() under random similarities.

#include "csgtile/kernel/curve.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <numbers>
#include <random>

#include <vector>
#include "random_geometry.h"

#include "csgtile/kernel/curve2d.h"
#include "csgtile/kernel/frame.h"

namespace csgtile::kernel {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kTwoPi = 2.0 * std::numbers::pi;

using test::expect_near;
using test::random_frame;
using test::random_point;
using test::random_similarity;
using test::random_unit;

/// Golden-section refinement of a 1-D maximum found by sampling, kept inside [lo, hi].
double refine_max_1d(const std::function<double(double)>& f, double t, double h, double lo,
                     double hi) {
  double a = std::max(lo, t - h);
  double b = std::min(hi, t + h);
  const double r = 0.5 * (std::sqrt(5.0) - 1.0);
  double c = b - r * (b - a);
  double d = a + r * (b - a);
  for (int i = 0; i < 200 && b - a > 1e-15; ++i) {
    if (f(c) > f(d)) {
      b = d;
    } else {
      a = c;
    }
    c = b - r * (b - a);
    d = a + r * (b - a);
  }
  return std::max({f(a), f(b), f(t), f(lo), f(hi)});
}

/// Maximum of f over [t0, t1] by dense sampling refined around the best samples.
double sampled_max(const std::function<double(double)>& f, double t0, double t1,
                   int samples = 4000) {
  std::vector<std::pair<double, double>> values;
  const double h = (t1 - t0) / samples;
  for (int i = 0; i <= samples; ++i) {
    const double t = t0 + h * i;
    values.emplace_back(f(t), t);
  }
  std::sort(values.begin(), values.end(), std::greater<>());
  double best = values.front().first;
  for (int k = 0; k < 4; ++k) {
    best =
        std::max(best, refine_max_1d(f, values[static_cast<std::size_t>(k)].second, 2 * h, t0, t1));
  }
  return best;
}

// ---- Frame --------------------------------------------------------------------------------

TEST(FrameTest, FromZIsOrthonormalAndRightHanded) {
  std::mt19937 rng(101);
  for (int i = 0; i < 100; ++i) {
    const Vec3 z = random_unit(rng) * 3.0;
    const Vec3 hint = random_unit(rng);
    const Frame f = Frame::from_z(Vec3(1, 2, 3), z, hint);
    EXPECT_NEAR(f.x.norm(), 1.0, 1e-15);
    EXPECT_NEAR(f.y.norm(), 1.0, 1e-15);
    expect_near(f.z, z.normalized(), 1e-15);
    EXPECT_NEAR(f.x.dot(f.z), 0.0, 1e-15);
    expect_near(f.x.cross(f.y), f.z, 4e-16 * 8);
    // x keeps the hint's direction within the plane ⊥ z.
    EXPECT_GT(f.x.dot(hint), 0.0);
    expect_near(f.origin, Vec3(1, 2, 3), 0.0);
  }
}

TEST(FrameTest, FromZWithHintParallelToZPicksAPerpendicular) {
  for (const Vec3& z :
       std::vector<Vec3>{Vec3::UnitX(), Vec3::UnitY(), Vec3::UnitZ(), Vec3(1, 1, 1)}) {
    const Frame f = Frame::from_z(Vec3::Zero(), z, -2.0 * z);
    EXPECT_NEAR(f.x.norm(), 1.0, 1e-15);
    EXPECT_NEAR(f.x.dot(f.z), 0.0, 1e-15);
    expect_near(f.x.cross(f.y), f.z, 1e-15);
  }
}

TEST(FrameTest, DefaultHintGivesTheStandardFrame) {
  const Frame f = Frame::from_z(Vec3::Zero(), Vec3(0, 0, 2));
  expect_near(f.x, Vec3::UnitX(), 0.0);
  expect_near(f.y, Vec3::UnitY(), 0.0);
  expect_near(f.z, Vec3::UnitZ(), 0.0);
}

TEST(FrameTest, TransformedMovesOriginAsPointAndAxesAsDirections) {
  std::mt19937 rng(102);
  const Frame f = random_frame(rng);
  const Location loc = random_similarity(rng);
  const Frame g = f.transformed(loc);
  expect_near(g.origin, loc.apply_point(f.origin), 1e-12);
  expect_near(g.x, loc.rotation() * f.x, 1e-15);
  expect_near(g.y, loc.rotation() * f.y, 1e-15);
  expect_near(g.z, loc.rotation() * f.z, 1e-15);
  EXPECT_NEAR(g.x.norm(), 1.0, 1e-14);
  expect_near(g.x.cross(g.y), g.z, 1e-14);
}

// ---- Line ---------------------------------------------------------------------------------

TEST(CurveLineTest, EvaluatesWithUnitDirection) {
  const LineCurve line(Vec3(1, 2, 3), Vec3(0, 3, 4));
  expect_near(line.direction(), Vec3(0, 0.6, 0.8), 1e-16);
  expect_near(line.point(5.0), Vec3(1, 5, 7), 1e-14);
  expect_near(line.derivative(2.0), Vec3(0, 0.6, 0.8), 1e-16);
  expect_near(line.second_derivative(2.0), Vec3::Zero(), 0.0);
  EXPECT_EQ(line.period(), 0.0);
  EXPECT_EQ(line.first_parameter(), -std::numeric_limits<double>::infinity());
  EXPECT_EQ(line.last_parameter(), std::numeric_limits<double>::infinity());
  EXPECT_EQ(line.kind(), CurveKind::Line);
}

TEST(CurveLineTest, ClosestParameterProjectsAndClamps) {
  const LineCurve line(Vec3::Zero(), Vec3::UnitX());
  EXPECT_DOUBLE_EQ(line.closest_parameter(Vec3(2.5, 7, -1), -10, 10), 2.5);
  EXPECT_DOUBLE_EQ(line.closest_parameter(Vec3(2.5, 7, -1), 3, 10), 3.0);
  EXPECT_DOUBLE_EQ(line.closest_parameter(Vec3(-20, 0, 0), -10, 10), -10.0);
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_DOUBLE_EQ(line.closest_parameter(Vec3(-20, 1, 0), -inf, inf), -20.0);
}

TEST(CurveLineTest, SupportBoundsAndLength) {
  const LineCurve line(Vec3(1, 1, 1), Vec3(1, -1, 0));
  const double s = std::sqrt(0.5);
  EXPECT_NEAR(line.support(Vec3::UnitX(), -2, 4), 1 + 4 * s, 1e-15);
  EXPECT_NEAR(line.support(Vec3::UnitY(), -2, 4), 1 + 2 * s, 1e-15);
  EXPECT_NEAR(line.support(Vec3::UnitZ(), -2, 4), 1.0, 0.0);
  const BoundingBox b = line.bounds(-2, 4);
  expect_near(b.min, Vec3(1 - 2 * s, 1 - 4 * s, 1), 1e-15);
  expect_near(b.max, Vec3(1 + 4 * s, 1 + 2 * s, 1), 1e-15);
  // A direction orthogonal to the line never multiplies an infinite bound.
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_EQ(line.support(Vec3::UnitZ(), -inf, inf), 1.0);
  EXPECT_EQ(line.support(Vec3::UnitX(), -inf, inf), inf);
  EXPECT_DOUBLE_EQ(line.length(-2, 4), 6.0);
  EXPECT_DOUBLE_EQ(line.length(4, -2), 6.0);
}

TEST(CurveLineTest, TransformedScalesTheArcLengthParameter) {
  std::mt19937 rng(103);
  const LineCurve line(random_point(rng, 3), random_unit(rng));
  for (int i = 0; i < 10; ++i) {
    const Location loc = random_similarity(rng);
    const CurvePtr moved = line.transformed(loc);
    ASSERT_EQ(moved->kind(), CurveKind::Line);
    for (double t : {-3.0, 0.0, 0.7, 5.0}) {
      expect_near(moved->point(loc.scale() * t), loc.apply_point(line.point(t)), 1e-12);
    }
    EXPECT_NEAR(moved->derivative(0).norm(), 1.0, 1e-15);
  }
}

// ---- Circle -------------------------------------------------------------------------------

TEST(CurveCircleTest, EvaluatesTheDocumentedParametrisation) {
  std::mt19937 rng(201);
  const Frame f = random_frame(rng);
  const CircleCurve c(f, 2.5);
  EXPECT_EQ(c.kind(), CurveKind::Circle);
  EXPECT_DOUBLE_EQ(c.period(), kTwoPi);
  EXPECT_EQ(c.first_parameter(), 0.0);
  EXPECT_DOUBLE_EQ(c.last_parameter(), kTwoPi);
  for (double t : {0.0, 0.3, kPi / 2, 2.0, 4.0, 7.0}) {
    expect_near(c.point(t), f.origin + 2.5 * (std::cos(t) * f.x + std::sin(t) * f.y), 1e-14);
  }
  expect_near(c.point(0), f.origin + 2.5 * f.x, 1e-15);
  expect_near(c.point(kPi / 2), f.origin + 2.5 * f.y, 1e-14);
}

/// Central differences of point() and derivative() against derivative() and
/// second_derivative().
void expect_derivatives_match_finite_differences(const Curve& c, double t0, double t1) {
  constexpr double h = 1e-5;
  for (int i = 0; i <= 20; ++i) {
    const double t = t0 + (t1 - t0) * (i + 0.37) / 21.0;
    const Vec3 d1 = (c.point(t + h) - c.point(t - h)) / (2 * h);
    const Vec3 d2 = (c.derivative(t + h) - c.derivative(t - h)) / (2 * h);
    const double scale = 1.0 + c.derivative(t).norm() + c.second_derivative(t).norm();
    expect_near(c.derivative(t), d1, 1e-8 * scale);
    expect_near(c.second_derivative(t), d2, 1e-8 * scale);
  }
}

TEST(CurveCircleTest, DerivativesMatchFiniteDifferences) {
  std::mt19937 rng(202);
  const CircleCurve c(random_frame(rng), 1.7);
  expect_derivatives_match_finite_differences(c, -1, 8);
}

/// Random parameter ranges of periodic curves: starts anywhere in [-2π, 4π], lengths up to
/// and beyond a full turn.
std::pair<double, double> random_angle_range(std::mt19937& rng) {
  std::uniform_real_distribution<double> start(-kTwoPi, 2 * kTwoPi);
  std::uniform_real_distribution<double> length(0.05, 1.3 * kTwoPi);
  const double t0 = start(rng);
  return {t0, t0 + length(rng)};
}

TEST(CurveCircleTest, ClosestParameterRoundTripsOnTheArc) {
  std::mt19937 rng(203);
  const CircleCurve c(random_frame(rng), 3.0);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int i = 0; i < 500; ++i) {
    const auto [t0, t1] = random_angle_range(rng);
    const double t = t0 + (t1 - t0) * unit(rng);
    const double found = c.closest_parameter(c.point(t), t0, t1);
    EXPECT_GE(found, t0);
    EXPECT_LE(found, t1);
    expect_near(c.point(found), c.point(t), 1e-12);
  }
}

/// Checks closest_parameter against dense sampling of the arc: no sample is closer.
void expect_closest_beats_sampling(const Curve& c, const Vec3& p, double t0, double t1,
                                   double tolerance) {
  const double found = c.closest_parameter(p, t0, t1);
  EXPECT_GE(found, t0);
  EXPECT_LE(found, t1);
  const double best = -sampled_max([&](double t) { return -(c.point(t) - p).norm(); }, t0, t1);
  EXPECT_LE((c.point(found) - p).norm(), best + tolerance)
      << "t0 = " << t0 << " t1 = " << t1 << " found = " << found;
}

TEST(CurveCircleTest, ClosestParameterOffTheCurveBeatsDenseSampling) {
  std::mt19937 rng(204);
  const Frame f = random_frame(rng);
  const CircleCurve c(f, 2.0);
  for (int i = 0; i < 200; ++i) {
    const auto [t0, t1] = random_angle_range(rng);
    expect_closest_beats_sampling(c, f.origin + random_point(rng, 4.0), t0, t1, 1e-12);
  }
}

TEST(CurveCircleTest, ClosestParameterHandlesRangesPastTwoPiAndTheAxis) {
  const CircleCurve c(Frame{}, 1.0);
  // The angle 0.1 is reached as 2π + 0.1 in [π, 3π].
  EXPECT_NEAR(c.closest_parameter(Vec3(std::cos(0.1), std::sin(0.1), 5), kPi, 3 * kPi),
              kTwoPi + 0.1, 1e-14);
  // Outside the arc [0, π/2] the nearer end in angle wins.
  EXPECT_DOUBLE_EQ(c.closest_parameter(Vec3(1, -0.1, 0), 0, kPi / 2), 0.0);
  EXPECT_DOUBLE_EQ(c.closest_parameter(Vec3(-0.1, 1, 0), 0, kPi / 2), kPi / 2);
  // On the axis every point ties: the smallest parameter.
  EXPECT_DOUBLE_EQ(c.closest_parameter(Vec3(0, 0, 3), 0.5, 2.0), 0.5);
}

TEST(CurveCircleTest, SupportIsExactOnAnyAngleRange) {
  std::mt19937 rng(205);
  const Frame f = random_frame(rng);
  const CircleCurve c(f, 1.3);
  for (int i = 0; i < 200; ++i) {
    const auto [t0, t1] = random_angle_range(rng);
    const Vec3 w = random_unit(rng) * 2.0;
    const double support = c.support(w, t0, t1);
    EXPECT_NEAR(support, sampled_max([&](double t) { return c.point(t).dot(w); }, t0, t1), 1e-12);
  }
  // The quarter-turn-offset full range [π/2, 5π/2] covers every angle.
  const CircleCurve unit(Frame{}, 1.0);
  EXPECT_DOUBLE_EQ(unit.support(Vec3::UnitX(), kPi / 2, 5 * kPi / 2), 1.0);
  EXPECT_DOUBLE_EQ(unit.support(-Vec3::UnitX(), kPi / 2, 5 * kPi / 2), 1.0);
}

TEST(CurveCircleTest, BoundsOfArcsAreExact) {
  const CircleCurve c(Frame::from_z(Vec3(1, 1, 1), Vec3::UnitZ()), 2.0);
  // Quarter arc from angle 0 to π/2: a corner box.
  BoundingBox b = c.bounds(0, kPi / 2);
  expect_near(b.min, Vec3(1, 1, 1), 1e-15);
  expect_near(b.max, Vec3(3, 3, 1), 1e-15);
  // Arc [π/4, 3π/4] reaches the top at π/2 only.
  b = c.bounds(kPi / 4, 3 * kPi / 4);
  expect_near(b.min, Vec3(1 - std::sqrt(2.0), 1 + std::sqrt(2.0), 1), 1e-14);
  expect_near(b.max, Vec3(1 + std::sqrt(2.0), 3, 1), 1e-14);
  // Crossing 2π.
  b = c.bounds(3 * kPi / 2, 5 * kPi / 2);
  expect_near(b.min, Vec3(1, -1, 1), 1e-14);
  expect_near(b.max, Vec3(3, 3, 1), 1e-14);
}

TEST(CurveCircleTest, LengthIsRadiusTimesAngle) {
  const CircleCurve c(Frame{}, 2.0);
  EXPECT_DOUBLE_EQ(c.length(0, kTwoPi), 4 * kPi);
  EXPECT_DOUBLE_EQ(c.length(1, 2.5), 3.0);
}

TEST(CurveCircleTest, TransformedKeepsTheAngleAndScalesTheRadius) {
  std::mt19937 rng(206);
  const CircleCurve c(random_frame(rng), 1.5);
  for (int i = 0; i < 10; ++i) {
    const Location loc = random_similarity(rng);
    const CurvePtr moved = c.transformed(loc);
    ASSERT_EQ(moved->kind(), CurveKind::Circle);
    EXPECT_NEAR(static_cast<const CircleCurve&>(*moved).radius(), 1.5 * loc.scale(), 1e-14);
    for (double t = -1.0; t < 7.0; t += 0.9) {
      expect_near(moved->point(t), loc.apply_point(c.point(t)), 1e-12 * (1 + loc.scale()) * 20);
      expect_near(moved->derivative(t), loc.apply_vector(c.derivative(t)), 1e-12 * 10);
    }
  }
}

// ---- Ellipse ------------------------------------------------------------------------------

TEST(CurveEllipseTest, EvaluatesTheDocumentedParametrisation) {
  std::mt19937 rng(301);
  const Frame f = random_frame(rng);
  const EllipseCurve e(f, 3.0, 1.25);
  EXPECT_EQ(e.kind(), CurveKind::Ellipse);
  EXPECT_DOUBLE_EQ(e.period(), kTwoPi);
  for (double t : {0.0, 0.4, 1.0, 3.0, 5.5}) {
    expect_near(e.point(t), f.origin + 3.0 * std::cos(t) * f.x + 1.25 * std::sin(t) * f.y, 1e-14);
  }
  expect_derivatives_match_finite_differences(e, -2, 9);
}

/// A random ellipse with a ≥ b, including very eccentric ones.
EllipseCurve random_ellipse(std::mt19937& rng) {
  std::uniform_real_distribution<double> major(0.5, 4.0);
  std::uniform_real_distribution<double> ratio(0.02, 1.0);
  const double a = major(rng);
  return EllipseCurve(random_frame(rng), a, a * ratio(rng));
}

TEST(CurveEllipseTest, ClosestParameterRoundTripsTo1e12) {
  std::mt19937 rng(302);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int i = 0; i < 1000; ++i) {
    const EllipseCurve e = random_ellipse(rng);
    const auto [t0, t1] = random_angle_range(rng);
    const double t = t0 + (t1 - t0) * unit(rng);
    const double found = e.closest_parameter(e.point(t), t0, t1);
    EXPECT_GE(found, t0);
    EXPECT_LE(found, t1);
    expect_near(e.point(found), e.point(t), 1e-12 * e.major_radius());
  }
}

TEST(CurveEllipseTest, ClosestParameterOffTheCurveBeatsDenseSampling) {
  std::mt19937 rng(303);
  for (int i = 0; i < 300; ++i) {
    const EllipseCurve e = random_ellipse(rng);
    const auto [t0, t1] = random_angle_range(rng);
    const Frame& f = e.frame();
    // Points inside the evolute (up to four normals), outside, and off the plane.
    std::uniform_real_distribution<double> near(-1.2, 1.2);
    const Vec3 p = f.origin + near(rng) * e.major_radius() * f.x +
                   near(rng) * e.minor_radius() * f.y + near(rng) * f.z;
    expect_closest_beats_sampling(e, p, t0, t1, 1e-12);
  }
}

TEST(CurveEllipseTest, ClosestParameterOnTheAxesAndAtTheCentre) {
  const EllipseCurve e(Frame{}, 2.0, 1.0);
  // On the major axis inside the evolute (|x| < (a² − b²)/a = 1.5): two symmetric normals.
  // cos t = x·a / (a² − b²).
  const double x = 0.9;
  const double t = e.closest_parameter(Vec3(x, 0, 0), 0, kTwoPi);
  EXPECT_NEAR(std::cos(t), x * 2.0 / 3.0, 1e-12);
  EXPECT_NEAR(t, std::acos(x * 2.0 / 3.0), 1e-12);  // the smaller of the two ties
  // Beyond the evolute the vertex is closest.
  EXPECT_NEAR(e.closest_parameter(Vec3(1.8, 0, 0), 0, kTwoPi), 0.0, 1e-12);
  // On the minor axis: the co-vertex.
  EXPECT_NEAR(e.closest_parameter(Vec3(0, 0.5, 0), 0, kTwoPi), kPi / 2, 1e-12);
  EXPECT_NEAR(e.closest_parameter(Vec3(0, -0.5, 0), 0, kTwoPi), 3 * kPi / 2, 1e-12);
  // At the centre: both co-vertices at distance b; the smaller parameter wins.
  EXPECT_NEAR(e.closest_parameter(Vec3(0, 0, 0), 0, kTwoPi), kPi / 2, 1e-12);
}

TEST(CurveEllipseTest, SupportIsExactOnAnyAngleRange) {
  std::mt19937 rng(304);
  for (int i = 0; i < 200; ++i) {
    const EllipseCurve e = random_ellipse(rng);
    const auto [t0, t1] = random_angle_range(rng);
    const Vec3 w = random_unit(rng);
    EXPECT_NEAR(e.support(w, t0, t1),
                sampled_max([&](double t) { return e.point(t).dot(w); }, t0, t1), 1e-12);
  }
}

/// Perimeter 4·a·E(e) with the complete elliptic integral E from the arithmetic–geometric
/// mean, independent of the quadrature under test.
double ellipse_perimeter(double a, double b) {
  const double k2 = 1.0 - (b * b) / (a * a);
  double an = 1.0;
  double gn = std::sqrt(1.0 - k2);
  double power = 0.5;
  double sum = 0.5 * k2;
  for (int i = 0; i < 40; ++i) {
    const double c = 0.5 * (an - gn);
    const double next = 0.5 * (an + gn);
    gn = std::sqrt(an * gn);
    an = next;
    power *= 2.0;
    sum += power * c * c;
    if (c < 1e-300) break;
  }
  return 4.0 * a * (kPi / (2.0 * an)) * (1.0 - sum);
}

TEST(CurveEllipseTest, LengthMatchesTheEllipticIntegral) {
  for (const auto& [a, b] : std::vector<std::pair<double, double>>{
           {1.0, 1.0}, {2.0, 1.0}, {5.0, 0.3}, {3.0, 0.01}, {1.0, 0.999}}) {
    const EllipseCurve e(Frame{}, a, b);
    const double exact = ellipse_perimeter(a, b);
    EXPECT_NEAR(e.length(0, kTwoPi), exact, 1e-12 * exact) << a << " x " << b;
    // Quarter symmetry and additivity on ranges that do not start at a quadrant.
    EXPECT_NEAR(e.length(kPi / 2, kPi), exact / 4, 1e-12 * exact);
    EXPECT_NEAR(e.length(0.3, 2.0) + e.length(2.0, 7.1), e.length(0.3, 7.1), 1e-12 * exact);
    EXPECT_NEAR(e.length(-kTwoPi, 0.0), exact, 1e-12 * exact);
  }
}

TEST(CurveEllipseTest, TransformedScalesBothRadii) {
  std::mt19937 rng(305);
  const EllipseCurve e(random_frame(rng), 2.0, 0.5);
  const Location loc = random_similarity(rng);
  const CurvePtr moved = e.transformed(loc);
  ASSERT_EQ(moved->kind(), CurveKind::Ellipse);
  const auto& m = static_cast<const EllipseCurve&>(*moved);
  EXPECT_NEAR(m.major_radius(), 2.0 * loc.scale(), 1e-14);
  EXPECT_NEAR(m.minor_radius(), 0.5 * loc.scale(), 1e-14);
  for (double t = -1.0; t < 7.0; t += 0.7) {
    expect_near(moved->point(t), loc.apply_point(e.point(t)), 1e-11);
  }
  EXPECT_NEAR(moved->length(0, 1), loc.scale() * e.length(0, 1), 1e-12 * moved->length(0, 1));
}

// ---- Polyline -----------------------------------------------------------------------------

PolylineCurve zigzag() {
  return PolylineCurve({Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(1, 2, 0), Vec3(3, 2, 1)}, 0.01);
}

TEST(CurvePolylineTest, EvaluatesSegmentBySegment) {
  const PolylineCurve p = zigzag();
  EXPECT_EQ(p.kind(), CurveKind::Polyline);
  EXPECT_EQ(p.first_parameter(), 0.0);
  EXPECT_EQ(p.last_parameter(), 3.0);
  EXPECT_EQ(p.period(), 0.0);
  expect_near(p.point(0), Vec3(0, 0, 0), 0.0);
  expect_near(p.point(1), Vec3(1, 0, 0), 0.0);
  expect_near(p.point(3), Vec3(3, 2, 1), 0.0);
  expect_near(p.point(1.25), Vec3(1, 0.5, 0), 1e-15);
  expect_near(p.point(2.5), Vec3(2, 2, 0.5), 1e-15);
  expect_near(p.derivative(0.5), Vec3(1, 0, 0), 0.0);
  expect_near(p.derivative(1.0), Vec3(0, 2, 0), 0.0);  // a vertex: the segment it starts
  expect_near(p.derivative(3.0), Vec3(2, 0, 1), 0.0);  // the end: the last segment
  expect_near(p.second_derivative(1.5), Vec3::Zero(), 0.0);
}

TEST(CurvePolylineTest, ClosestParameterIsTheNearestSegmentPoint) {
  const PolylineCurve p = zigzag();
  EXPECT_NEAR(p.closest_parameter(Vec3(0.4, -1, 0), 0, 3), 0.4, 1e-15);
  EXPECT_NEAR(p.closest_parameter(Vec3(0.5, 1.5, 0), 0, 3), 1.75, 1e-15);
  // Projected inside the last segment: (2, 1.5, 0) − (1, 2, 0) along (2, 0, 1) gives 0.4.
  EXPECT_NEAR(p.closest_parameter(Vec3(2, 1.5, 0), 0, 3), 2.4, 1e-15);
  // Restricted to [2, 3] the point nearest the middle segment clamps to the range start.
  EXPECT_DOUBLE_EQ(p.closest_parameter(Vec3(0.5, 1.5, 0), 2, 3), 2.0);
  // Inside a range that starts mid-segment.
  EXPECT_NEAR(p.closest_parameter(Vec3(0, 0, 0), 0.5, 3), 0.5, 1e-15);
  std::mt19937 rng(401);
  std::uniform_real_distribution<double> range(0.0, 3.0);
  for (int i = 0; i < 200; ++i) {
    double t0 = range(rng);
    double t1 = range(rng);
    if (t1 < t0) std::swap(t0, t1);
    expect_closest_beats_sampling(p, random_point(rng, 3.0), t0, t1, 1e-12);
  }
}

TEST(CurvePolylineTest, SupportUsesRangeEndsAndInteriorVertices) {
  const PolylineCurve p = zigzag();
  EXPECT_DOUBLE_EQ(p.support(Vec3::UnitY(), 0, 3), 2.0);
  EXPECT_DOUBLE_EQ(p.support(Vec3::UnitY(), 0, 1.5), 1.0);
  EXPECT_DOUBLE_EQ(p.support(Vec3(-1, 0, 0), 0.5, 3), -0.5);
  EXPECT_DOUBLE_EQ(p.support(Vec3(1, 1, 0), 0.2, 2.2), 3.4);
  const BoundingBox b = p.bounds(0.5, 2.5);
  expect_near(b.min, Vec3(0.5, 0, 0), 1e-15);
  expect_near(b.max, Vec3(2, 2, 0.5), 1e-15);
}

TEST(CurvePolylineTest, LengthIsExact) {
  const PolylineCurve p = zigzag();
  EXPECT_DOUBLE_EQ(p.length(0, 3), 1.0 + 2.0 + std::sqrt(5.0));
  EXPECT_DOUBLE_EQ(p.length(0.5, 1.5), 0.5 + 1.0);
  EXPECT_NEAR(p.length(2.25, 2.75), 0.5 * std::sqrt(5.0), 1e-15);
}

TEST(CurvePolylineTest, TransformedMovesPointsAndScalesTolerance) {
  std::mt19937 rng(402);
  const PolylineCurve p = zigzag();
  const Location loc = random_similarity(rng);
  const CurvePtr moved = p.transformed(loc);
  ASSERT_EQ(moved->kind(), CurveKind::Polyline);
  EXPECT_NEAR(static_cast<const PolylineCurve&>(*moved).tolerance(), 0.01 * loc.scale(), 1e-16);
  for (double t = 0; t <= 3.0; t += 0.25) {
    expect_near(moved->point(t), loc.apply_point(p.point(t)), 1e-12);
  }
  EXPECT_NEAR(moved->length(0, 3), loc.scale() * p.length(0, 3), 1e-12);
}

// ---- Bounds and random ranges on all kinds ------------------------------------------------

TEST(CurveBoundsTest, ContainAndTouchDenseSamples) {
  std::mt19937 rng(501);
  for (int i = 0; i < 60; ++i) {
    const auto [t0, t1] = random_angle_range(rng);
    const CircleCurve c(random_frame(rng), 1.5);
    const EllipseCurve e = random_ellipse(rng);
    for (const Curve* curve : {static_cast<const Curve*>(&c), static_cast<const Curve*>(&e)}) {
      const BoundingBox b = curve->bounds(t0, t1);
      for (int k = 0; k < 3; ++k) {
        const Vec3 axis = Vec3::Unit(k);
        EXPECT_NEAR(b.max[k], sampled_max([&](double t) { return curve->point(t)[k]; }, t0, t1),
                    1e-12);
        EXPECT_NEAR(b.min[k], -sampled_max([&](double t) { return -curve->point(t)[k]; }, t0, t1),
                    1e-12);
        EXPECT_DOUBLE_EQ(b.max[k], curve->support(axis, t0, t1));
      }
    }
  }
}

// ---- 2D curves ----------------------------------------------------------------------------

TEST(Curve2dTest, CircleFollowsItsSense) {
  const Circle2d ccw(Vec2(1, 2), 3.0);
  const Circle2d cw(Vec2(1, 2), 3.0, -1);
  EXPECT_EQ(ccw.sense(), 1);
  EXPECT_EQ(cw.sense(), -1);
  EXPECT_EQ(Circle2d(Vec2::Zero(), 1.0, -7).sense(), -1);
  for (double t : {0.0, 0.5, 2.0, 4.0}) {
    EXPECT_LE((ccw.point(t) - (Vec2(1, 2) + 3.0 * Vec2(std::cos(t), std::sin(t)))).norm(), 1e-15);
    EXPECT_LE((cw.point(t) - (Vec2(1, 2) + 3.0 * Vec2(std::cos(t), -std::sin(t)))).norm(), 1e-15);
    constexpr double h = 1e-6;
    for (const Circle2d* c : {&ccw, &cw}) {
      const Vec2 fd = (c->point(t + h) - c->point(t - h)) / (2 * h);
      EXPECT_LE((c->derivative(t) - fd).norm(), 1e-8);
    }
  }
  EXPECT_EQ(ccw.kind(), Curve2dKind::Circle);
}

TEST(Curve2dTest, PolylineAndLine) {
  const Polyline2d p({Vec2(0, 0), Vec2(2, 0), Vec2(2, 1)});
  EXPECT_EQ(p.kind(), Curve2dKind::Polyline);
  EXPECT_LE((p.point(0.5) - Vec2(1, 0)).norm(), 1e-15);
  EXPECT_LE((p.point(1.5) - Vec2(2, 0.5)).norm(), 1e-15);
  EXPECT_LE((p.point(2.0) - Vec2(2, 1)).norm(), 0.0);
  EXPECT_LE((p.derivative(0.2) - Vec2(2, 0)).norm(), 0.0);
  EXPECT_LE((p.derivative(1.0) - Vec2(0, 1)).norm(), 0.0);
  EXPECT_LE((p.derivative(2.0) - Vec2(0, 1)).norm(), 0.0);
  const Line2d l(Vec2(1, 1), Vec2(0, 2));
  EXPECT_LE((l.point(1.5) - Vec2(1, 4)).norm(), 0.0);
}

}  // namespace
}  // namespace csgtile::kernel
