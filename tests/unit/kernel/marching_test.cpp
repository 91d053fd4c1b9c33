// Marching surface–surface intersection (kernel/src/boolean/marching.*): every traced point
// on both surfaces, loops closed, chords within the requested sag, branches counted.

#include "boolean/marching.h"

#include <gtest/gtest.h>

#include <cmath>

namespace csgtile::kernel::detail {
namespace {

constexpr double kTol = 1e-7;
constexpr double kSag = 1e-5;

double distance_to(const Surface& s, const Vec3& p) {
  const Vec2 uv = s.closest_parameters(p);
  return (s.point(uv.x(), uv.y()) - p).norm();
}

BoundingBox box(const Vec3& lo, const Vec3& hi) {
  BoundingBox b;
  b.add(lo);
  b.add(hi);
  return b;
}

// Checks every curve: points on both surfaces (and at their stored parameters), chord
// midpoints within the reported deviation, which is within the sag.
void expect_traced(const MarchResult& r, const Surface& a, const Surface& b) {
  ASSERT_TRUE(r.ok) << r.reason;
  for (const MarchedCurve& c : r.curves) {
    ASSERT_EQ(c.points.size(), c.uv_a.size());
    ASSERT_EQ(c.points.size(), c.uv_b.size());
    EXPECT_LE(c.deviation, kSag);
    for (std::size_t i = 0; i < c.points.size(); ++i) {
      EXPECT_LE(distance_to(a, c.points[i]), 1e-9);
      EXPECT_LE(distance_to(b, c.points[i]), 1e-9);
      EXPECT_LE((a.point(c.uv_a[i].x(), c.uv_a[i].y()) - c.points[i]).norm(), 1e-9);
      EXPECT_LE((b.point(c.uv_b[i].x(), c.uv_b[i].y()) - c.points[i]).norm(), 1e-9);
    }
    for (std::size_t i = 0; i + 1 < c.points.size(); ++i) {
      const Vec3 mid = 0.5 * (c.points[i] + c.points[i + 1]);
      EXPECT_LE(distance_to(a, mid), kSag * 1.01);
      EXPECT_LE(distance_to(b, mid), kSag * 1.01);
    }
    if (c.closed) {
      EXPECT_EQ(c.points.front(), c.points.back());
    }
  }
}

TEST(Marching, UnequalCrossingCylindersGiveTwoLoops) {
  const CylinderSurface big(Frame::from_z(Vec3(0, 0, -3), Vec3::UnitZ()), 1.0);
  const CylinderSurface small(Frame::from_z(Vec3(-3, 0, 0), Vec3::UnitX()), 0.6);
  const MarchResult r =
      march_intersection(big, small, box({-1.2, -1.2, -1.2}, {1.2, 1.2, 1.2}), kTol, kSag);
  expect_traced(r, big, small);
  ASSERT_EQ(r.curves.size(), 2u);
  for (const auto& c : r.curves) {
    EXPECT_TRUE(c.closed);
    EXPECT_GT(c.points.size(), 20u);
  }
}

TEST(Marching, SkewCylindersGiveOneLoop) {
  // Axes 0.5 apart: the thinner cylinder bites into the side of the thicker one.
  const CylinderSurface a(Frame::from_z(Vec3(0, 0, -3), Vec3::UnitZ()), 1.0);
  const CylinderSurface b(Frame::from_z(Vec3(-3, 0.9, 0), Vec3::UnitX()), 0.5);
  const MarchResult r =
      march_intersection(a, b, box({-1.5, -1.5, -1.5}, {1.5, 1.5, 1.5}), kTol, kSag);
  expect_traced(r, a, b);
  ASSERT_EQ(r.curves.size(), 1u);
  EXPECT_TRUE(r.curves[0].closed);
}

TEST(Marching, ObliquePlaneConeEllipse) {
  const ConeSurface cone(Frame::from_z(Vec3(0, 0, 0), Vec3::UnitZ()), 1.0, -0.4);
  const PlaneSurface plane(Frame::from_z(Vec3(0, 0, 0.6), Vec3(0.3, 0, 1)));
  const MarchResult r = march_intersection(plane, cone, box({-2, -2, -1}, {2, 2, 2}), kTol, kSag);
  expect_traced(r, plane, cone);
  ASSERT_EQ(r.curves.size(), 1u);
  EXPECT_TRUE(r.curves[0].closed);
}

TEST(Marching, OpenBranchesEndOutsideTheRegion) {
  // A vertical wall cutting a cone: a hyperbola leaving the region at both ends.
  const ConeSurface cone(Frame::from_z(Vec3(0, 0, 0), Vec3::UnitZ()), 1.0, -0.4);
  const PlaneSurface wall(Frame::from_z(Vec3(0.5, 0, 0), Vec3::UnitX()));
  const BoundingBox region = box({-2, -2, 0}, {2, 2, 2});
  const MarchResult r = march_intersection(wall, cone, region, kTol, kSag);
  expect_traced(r, wall, cone);
  ASSERT_EQ(r.curves.size(), 1u);
  EXPECT_FALSE(r.curves[0].closed);
  EXPECT_FALSE(region.contains(r.curves[0].points.front()));
  EXPECT_FALSE(region.contains(r.curves[0].points.back()));
}

TEST(Marching, ObliquePlaneTorus) {
  const TorusSurface torus(Frame(), 2.0, 0.5);
  const PlaneSurface plane(Frame::from_z(Vec3(0, 0, 0), Vec3(0.15, 0, 1)));
  const MarchResult r = march_intersection(plane, torus, box({-3, -3, -1}, {3, 3, 1}), kTol, kSag);
  expect_traced(r, plane, torus);
  EXPECT_EQ(r.curves.size(), 2u);  // the inner and the outer loop
  for (const auto& c : r.curves) EXPECT_TRUE(c.closed);
}

TEST(Marching, SphereAndOffAxisCylinder) {
  const SphereSurface sphere(Frame(), 1.0);
  // A thin tilted drill through the sphere, well inside it at the equator: a loop where it
  // enters and one where it leaves.
  const CylinderSurface cyl(Frame::from_z(Vec3(0.3, 0, -3), Vec3(0.1, 0, 1)), 0.3);
  const MarchResult r =
      march_intersection(sphere, cyl, box({-1.2, -1.2, -1.2}, {1.2, 1.2, 1.2}), kTol, kSag);
  expect_traced(r, sphere, cyl);
  EXPECT_EQ(r.curves.size(), 2u);
}

TEST(Marching, DisjointSurfacesGiveNothing) {
  const SphereSurface a(Frame(), 1.0);
  const CylinderSurface b(Frame::from_z(Vec3(3, 0, -3), Vec3::UnitZ()), 0.5);
  const MarchResult r =
      march_intersection(a, b, box({-1.2, -1.2, -1.2}, {1.2, 1.2, 1.2}), kTol, kSag);
  ASSERT_TRUE(r.ok);
  EXPECT_TRUE(r.curves.empty());
}

TEST(Marching, Deterministic) {
  const CylinderSurface big(Frame::from_z(Vec3(0, 0, -3), Vec3::UnitZ()), 1.0);
  const CylinderSurface small(Frame::from_z(Vec3(-3, 0.2, 0.1), Vec3(1, 0.1, 0)), 0.6);
  const BoundingBox region = box({-1.2, -1.2, -1.2}, {1.2, 1.2, 1.2});
  const MarchResult a = march_intersection(big, small, region, kTol, kSag);
  const MarchResult b = march_intersection(big, small, region, kTol, kSag);
  ASSERT_EQ(a.curves.size(), b.curves.size());
  for (std::size_t i = 0; i < a.curves.size(); ++i)
    EXPECT_EQ(a.curves[i].points, b.curves[i].points);
}

}  // namespace
}  // namespace csgtile::kernel::detail
