// Extrusions and revolutions from several shapes: an L-shaped building seen from above and
// its sides is one extrusion, a gabled house (a pentagon swept horizontally) is one, a vase
// of coaxial cylinder, cone and cylinder is one revolution, a plain box stays a box, and
// degenerate input makes none and says why.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "csgtile/fit/fit.h"
#include "csgtile/kernel/polygon2d.h"
#include "fit_clouds.h"

namespace csgtile::fit {
namespace {

using kernel::PrimitiveType;
using kernel::Vec2;
using kernel::Vec3;
using testing::Cloud;
using testing::flat_ground;

FittedPrimitives fit(const Cloud& c, std::uint64_t seed = 3) {
  RansacOptions o;
  o.epsilon = 0.01;
  o.min_points = 50;
  o.seed = seed;
  auto shapes = detect_shapes(c.points, c.normals, o);
  EXPECT_TRUE(shapes.ok());
  return primitives_from_shapes(c.points, c.normals, shapes.value(), PrimitiveOptions{}, o, 0);
}

long long count(const FittedPrimitives& f, PrimitiveType t) {
  return f.per_type[static_cast<std::size_t>(t)];
}

bool inside(const Vec2& p, const std::vector<Vec2>& ring) { return kernel::inside_ring(p, ring); }

// Walls (outward normals for a counter-clockwise ring) of a vertical prism, heights [0, h].
Cloud walls(const std::vector<Vec2>& ring, double h, double spacing, std::uint64_t seed) {
  Cloud c;
  for (std::size_t i = 0; i < ring.size(); ++i) {
    const Vec2 a = ring[i], b = ring[(i + 1) % ring.size()];
    c.append(testing::rectangle_cloud(Vec3(a.x(), a.y(), 0.0),
                                      Vec3(b.x() - a.x(), b.y() - a.y(), 0.0), Vec3(0.0, 0.0, h),
                                      spacing, 0.002, seed + i));
  }
  return c;
}

TEST(FitExtrusion, LShapedBuildingIsOneExtrusion) {
  const std::vector<Vec2> l{{0, 0}, {8, 0}, {8, 3}, {3, 3}, {3, 7}, {0, 7}};
  const double h = 4.0;
  Cloud c = walls(l, h, 0.08, 10);
  c.append(testing::rectangle_cloud(Vec3(0, 0, h), Vec3(8, 0, 0), Vec3(0, 3, 0), 0.08, 0.002, 20));
  c.append(testing::rectangle_cloud(Vec3(0, 3, h), Vec3(3, 0, 0), Vec3(0, 4, 0), 0.08, 0.002, 21));
  const auto f = fit(c);
  ASSERT_EQ(f.primitives.size(), 1U);
  const auto& p = f.primitives[0];
  ASSERT_EQ(p.spec.type, PrimitiveType::Extrusion);
  EXPECT_NEAR(p.spec.height, h, 0.02);
  EXPECT_LT(testing::line_angle_deg(p.spec.placement.rotation().col(2), Vec3::UnitZ()), 1.0);
  EXPECT_NEAR(p.spec.placement.apply_point(Vec3::Zero()).z(), 0.0, 0.02);
  // Footprint IoU on a 2 cm grid: the fitted profile placed in the world against the truth.
  long long both = 0, either = 0;
  for (double x = -1.0; x <= 9.0; x += 0.02) {
    for (double y = -1.0; y <= 8.0; y += 0.02) {
      const bool truth = inside(Vec2(x, y), l);
      const Vec3 local = p.spec.placement.inverse().apply_point(Vec3(x, y, 0.0));
      const bool fitted = inside(Vec2(local.x(), local.y()), p.spec.profile);
      both += truth && fitted ? 1 : 0;
      either += truth || fitted ? 1 : 0;
    }
  }
  EXPECT_GE(static_cast<double>(both) / static_cast<double>(either), 0.95);
  ASSERT_TRUE(p.quality.has_value());
  EXPECT_GT(p.quality->inliers, static_cast<long long>(0.9 * static_cast<double>(c.points.size())));
  EXPECT_LT(p.quality->rms, 0.005);
}

TEST(FitExtrusion, GabledHouseIsOneHorizontalExtrusion) {
  // Section in (y, z): walls at y = 0 and y = 6 up to 3 m, ridge at y = 3, z = 5; 8 m along x.
  const double length = 8.0;
  const Vec3 ex(length, 0, 0);
  Cloud c =
      testing::rectangle_cloud(Vec3(0, 0, 0), ex, Vec3(0, 0, 3), 0.08, 0.002, 1);  // y = 0: n -y
  c.append(
      testing::rectangle_cloud(Vec3(0, 6, 0), Vec3(0, 0, 3), ex, 0.08, 0.002, 2));  // y = 6: +y
  c.append(testing::rectangle_cloud(Vec3(0, 0, 3), ex, Vec3(0, 3, 2), 0.08, 0.002, 3));   // slope
  c.append(testing::rectangle_cloud(Vec3(0, 6, 3), Vec3(0, -3, 2), ex, 0.08, 0.002, 4));  // slope
  const auto f = fit(c);
  ASSERT_EQ(count(f, PrimitiveType::Extrusion), 1) << "primitives: " << f.primitives.size();
  EXPECT_EQ(f.primitives.size(), 1U);
  const auto& p = f.primitives[0].spec;
  EXPECT_LT(testing::line_angle_deg(p.placement.rotation().col(2), Vec3::UnitX()), 1.0);
  EXPECT_NEAR(p.height, length, 0.03);
  EXPECT_EQ(p.profile.size(), 5U);
  // The ridge is a profile vertex (in the world, within 3 cm of y = 3, z = 5).
  double ridge = INFINITY;
  for (const auto& v : p.profile) {
    const Vec3 w = p.placement.apply_point(Vec3(v.x(), v.y(), 0.0));
    ridge = std::min(ridge, std::hypot(w.y() - 3.0, w.z() - 5.0));
  }
  EXPECT_LT(ridge, 0.03);
}

// ρ of the fitted revolution's profile at world height z (axis along world z), the largest
// crossing of the profile with that height.
double profile_radius(const kernel::PrimitiveSpec& s, double z) {
  const double sign = s.placement.rotation().col(2).z() > 0.0 ? 1.0 : -1.0;
  const double z0 = s.placement.apply_point(Vec3::Zero()).z();
  double best = -1.0;
  for (std::size_t i = 0; i < s.profile.size(); ++i) {
    const Vec2 a = s.profile[i], b = s.profile[(i + 1) % s.profile.size()];
    const double za = z0 + sign * a.y(), zb = z0 + sign * b.y();
    if ((za - z) * (zb - z) > 0.0 || za == zb) continue;
    const double t = (z - za) / (zb - za);
    best = std::max(best, a.x() + t * (b.x() - a.x()));
  }
  return best;
}

// A flat roof seen from the air (10 points/m², no walls) over flat terrain at z = 0: points
// uniform over the footprint minus its holes.
Cloud roof_cloud(const std::vector<Vec2>& outer, const std::vector<Vec2>& hole, double z,
                 std::uint64_t seed) {
  double x0 = INFINITY, y0 = INFINITY, x1 = -INFINITY, y1 = -INFINITY;
  for (const auto& p : outer) {
    x0 = std::min(x0, p.x());
    y0 = std::min(y0, p.y());
    x1 = std::max(x1, p.x());
    y1 = std::max(y1, p.y());
  }
  testing::Draw d(seed);
  Cloud c;
  const int n = static_cast<int>(10.0 * (x1 - x0) * (y1 - y0));
  for (int i = 0; i < n; ++i) {
    const Vec2 q(d.uniform(x0, x1), d.uniform(y0, y1));
    if (!inside(q, outer) || (!hole.empty() && inside(q, hole))) continue;
    c.add(Vec3(q.x(), q.y(), z), Vec3::UnitZ(), 0.01, d);
  }
  return c;
}

// The roofs' points are exact to 1 cm: ε 3 cm.
const testing::AirborneFit kRoofs{.epsilon = 0.03};

// IoU of the fitted extrusion's footprint (placed) with the truth (outer minus hole).
double footprint_iou(const kernel::PrimitiveSpec& s, const std::vector<Vec2>& outer,
                     const std::vector<Vec2>& hole) {
  long long both = 0, either = 0;
  for (double x = -2.0; x <= 27.0; x += 0.05) {
    for (double y = -2.0; y <= 27.0; y += 0.05) {
      const bool truth = inside(Vec2(x, y), outer) && (hole.empty() || !inside(Vec2(x, y), hole));
      const Vec3 l = s.placement.inverse().apply_point(Vec3(x, y, 0.0));
      bool fitted = inside(Vec2(l.x(), l.y()), s.profile);
      for (const auto& h : s.holes) fitted = fitted && !inside(Vec2(l.x(), l.y()), h);
      both += truth && fitted ? 1 : 0;
      either += truth || fitted ? 1 : 0;
    }
  }
  return static_cast<double>(both) / static_cast<double>(either);
}

TEST(FitExtrusion, LShapedRoofSeenFromTheAirIsOneExtrusionToTheGround) {
  const std::vector<Vec2> l{{0, 0}, {20, 0}, {20, 8}, {8, 8}, {8, 20}, {0, 20}};
  const GroundGrid ground = flat_ground();
  const auto f = fit_airborne(roof_cloud(l, {}, 10.0, 7), ground, kRoofs);
  ASSERT_EQ(count(f, PrimitiveType::Extrusion), 1);
  EXPECT_EQ(f.primitives.size(), 1U);
  const auto& p = f.primitives[0].spec;
  std::string prof;
  for (const auto& v : p.profile) {
    const Vec3 w = p.placement.apply_point(Vec3(v.x(), v.y(), 0.0));
    prof += " (" + std::to_string(w.x()) + ", " + std::to_string(w.y()) + ")";
  }
  EXPECT_EQ(p.profile.size(), 6U) << prof;
  EXPECT_NEAR(p.height, 10.0, 0.02);
  EXPECT_NEAR(p.placement.apply_point(Vec3::Zero()).z(), 0.0, 0.02);
  EXPECT_GE(footprint_iou(p, l, {}), 0.95);
  // The same input gives the same extrusion; switched off, none.
  const auto again = fit_airborne(roof_cloud(l, {}, 10.0, 7), ground, kRoofs);
  ASSERT_EQ(again.primitives.size(), 1U);
  EXPECT_EQ(again.primitives[0].spec.profile, p.profile);
  EXPECT_EQ(count(fit_airborne(roof_cloud(l, {}, 10.0, 7), ground,
                               {.epsilon = 0.03, .extrusions = false}),
                  PrimitiveType::Extrusion),
            0);
}

TEST(FitExtrusion, CourtyardRoofHasAHole) {
  const std::vector<Vec2> outer{{0, 0}, {24, 0}, {24, 24}, {0, 24}};
  const std::vector<Vec2> yard{{8, 8}, {16, 8}, {16, 16}, {8, 16}};
  const GroundGrid ground = flat_ground();
  const auto f = fit_airborne(roof_cloud(outer, yard, 8.0, 8), ground, kRoofs);
  ASSERT_EQ(count(f, PrimitiveType::Extrusion), 1);
  const auto& p = f.primitives[0].spec;
  ASSERT_EQ(p.holes.size(), 1U);
  EXPECT_GE(footprint_iou(p, outer, yard), 0.95);
}

TEST(FitExtrusion, RectangularRoofStaysABox) {
  const std::vector<Vec2> rect{{0, 0}, {12, 0}, {12, 8}, {0, 8}};
  const GroundGrid ground = flat_ground();
  const auto f = fit_airborne(roof_cloud(rect, {}, 6.0, 9), ground, kRoofs);
  EXPECT_EQ(count(f, PrimitiveType::Extrusion), 0);
  EXPECT_EQ(count(f, PrimitiveType::Box), 1);
}

TEST(FitRevolution, VaseIsOneRevolution) {
  // ρ = 0.3 up to z = 0.4, a cone to ρ = 0.15 at z = 0.7, ρ = 0.15 up to z = 1.
  const Vec3 base(1.0, 2.0, 0.5);
  Cloud c = testing::cylinder_cloud(base, Vec3::UnitZ(), 0.3, 0.4, 0.0, 2 * std::numbers::pi, 5000,
                                    0.002, 1);
  c.append(testing::cone_cloud(base + Vec3(0, 0, 1.0), -Vec3::UnitZ(), std::atan(0.5), 0.3, 0.6,
                               4000, 0.002, 2));
  c.append(testing::cylinder_cloud(base + Vec3(0, 0, 0.7), Vec3::UnitZ(), 0.15, 0.3, 0.0,
                                   2 * std::numbers::pi, 3000, 0.002, 3));
  const auto f = fit(c);
  std::string why;
  for (const auto& r : f.rejected) why += r.what + ": " + r.reason + "; ";
  for (const auto& q : f.primitives)
    why += std::string(kernel::primitive_type_name(q.spec.type)) + " ";
  ASSERT_EQ(count(f, PrimitiveType::Revolution), 1) << "primitives: " << f.primitives.size() << why;
  EXPECT_EQ(f.primitives.size(), 1U);
  const auto& p = f.primitives[0].spec;
  EXPECT_LT(testing::line_angle_deg(p.placement.rotation().col(2), Vec3::UnitZ()), 1.0);
  EXPECT_NEAR(p.angle, 2 * std::numbers::pi, 1e-9);
  const Vec3 o = p.placement.apply_point(Vec3::Zero());
  EXPECT_LT(std::hypot(o.x() - base.x(), o.y() - base.y()), 0.02);
  for (double z = 0.02; z < 0.99; z += 0.05) {
    const double truth = z < 0.4 ? 0.3 : (z < 0.7 ? 0.3 - 0.5 * (z - 0.4) : 0.15);
    EXPECT_NEAR(profile_radius(p, base.z() + z), truth, 0.02) << "at z = " << z;
  }
}

// A column is a cylinder however the RANSAC splits it: two pieces of one radius on one axis
// are one surface, not a profile.
TEST(FitRevolution, ColumnInTwoPiecesStaysACylinder) {
  // Two halves of one column (one radius, one axis) seen from two sides at two heights.
  const Vec3 base(0.5, -1.0, 0.0);
  Cloud c = testing::cylinder_cloud(base, Vec3::UnitZ(), 0.25, 1.2, 0.0, std::numbers::pi, 3000,
                                    0.002, 1);
  c.append(testing::cylinder_cloud(base + Vec3(0, 0, 1.3), Vec3::UnitZ(), 0.25, 1.2,
                                   std::numbers::pi, 2 * std::numbers::pi, 3000, 0.002, 2));
  const auto f = fit(c);
  std::string why;
  for (const auto& r : f.rejected) why += r.what + ": " + r.reason + "; ";
  EXPECT_EQ(count(f, PrimitiveType::Revolution), 0) << why;
  EXPECT_GE(count(f, PrimitiveType::Cylinder), 1) << why;
}

TEST(FitRevolution, HalfTurnWallGetsItsAngle) {
  // Two coaxial half-cylinders (ρ 1.6 and 2.0, 1.5 m high) and the top between them: a
  // wall's bottom is not seen, its profile is closed across the gap.
  const Vec3 base(0, 0, 0);
  const double half = std::numbers::pi;
  Cloud c = testing::cylinder_cloud(base, Vec3::UnitZ(), 2.0, 1.5, 0.0, half, 6000, 0.002, 1);
  Cloud inner = testing::cylinder_cloud(base, Vec3::UnitZ(), 1.6, 1.5, 0.0, half, 5000, 0.002, 2);
  for (auto& n : inner.normals) n = -n;  // seen from inside the wall's curve
  c.append(inner);
  testing::Draw d(4);
  for (int i = 0; i < 2000; ++i) {
    const double phi = d.uniform(0.0, half), r = d.uniform(1.6, 2.0);
    // In the clouds' frame about z: φ = 0 along +y, φ = π/2 along -x.
    c.add(Vec3(-r * std::sin(phi), r * std::cos(phi), 1.5), Vec3::UnitZ(), 0.002, d);
  }
  const auto f = fit(c);
  ASSERT_EQ(count(f, PrimitiveType::Revolution), 1) << "primitives: " << f.primitives.size();
  const auto& p = f.primitives[0].spec;
  EXPECT_NEAR(p.angle, half, 0.05);
  // The turn starts on the +y axis (the clouds' φ = 0) and runs through -x.
  const Vec3 x = p.placement.rotation().col(0);
  const Vec3 mid =
      p.placement.apply_point(Vec3(1.8 * std::cos(p.angle / 2), 1.8 * std::sin(p.angle / 2), 0.7));
  std::string prof;
  for (const auto& v : p.profile)
    prof += " (" + std::to_string(v.x()) + "," + std::to_string(v.y()) + ")";
  EXPECT_LT(mid.x(), -1.7) << "x axis " << x.transpose() << " angle " << p.angle << " profile"
                           << prof << " origin "
                           << p.placement.apply_point(Vec3::Zero()).transpose();
  EXPECT_NEAR(profile_radius(p, 0.7), 2.0, 0.02);
}

TEST(FitExtrusion, PlainBoxStaysABox) {
  const std::vector<Vec2> rect{{0, 0}, {5, 0}, {5, 3}, {0, 3}};
  Cloud c = walls(rect, 2.5, 0.08, 30);
  c.append(
      testing::rectangle_cloud(Vec3(0, 0, 2.5), Vec3(5, 0, 0), Vec3(0, 3, 0), 0.08, 0.002, 40));
  const auto f = fit(c);
  EXPECT_EQ(count(f, PrimitiveType::Extrusion), 0);
  EXPECT_EQ(count(f, PrimitiveType::Box), 1);
}

TEST(FitExtrusion, DegenerateInputMakesNoExtrusionAndSaysWhy) {
  // Collinear points: no shape at all.
  Cloud line;
  testing::Draw d(5);
  for (int i = 0; i < 500; ++i) line.add(Vec3(0.01 * i, 0.0, 0.0), Vec3::UnitZ(), 0.0, d);
  RansacOptions o;
  o.epsilon = 0.01;
  o.min_points = 50;
  auto shapes = detect_shapes(line.points, line.normals, o);
  ASSERT_TRUE(shapes.ok());
  const auto none =
      primitives_from_shapes(line.points, line.normals, shapes.value(), PrimitiveOptions{}, o, 0);
  EXPECT_EQ(count(none, PrimitiveType::Extrusion), 0);
  EXPECT_TRUE(none.primitives.empty());
  // One plane only: no extrusion, and the plane is rejected with a reason.
  const Cloud plane =
      testing::rectangle_cloud(Vec3(0, 0, 0), Vec3(3, 0, 0), Vec3(0, 0, 2), 0.05, 0.002, 6);
  const auto one = fit(plane);
  EXPECT_EQ(count(one, PrimitiveType::Extrusion), 0);
  EXPECT_TRUE(one.primitives.empty());
  ASSERT_FALSE(one.rejected.empty());
  EXPECT_FALSE(one.rejected.front().reason.empty());
  // Walls that close no profile (three parallel planes): no extrusion, a reason.
  Cloud parallel;
  for (int k = 0; k < 3; ++k) {
    parallel.append(testing::rectangle_cloud(Vec3(0, 2.0 * k, 0), Vec3(3, 0, 0), Vec3(0, 0, 2),
                                             0.08, 0.002, 50 + static_cast<std::uint64_t>(k)));
  }
  const auto par = fit(parallel);
  EXPECT_EQ(count(par, PrimitiveType::Extrusion), 0);
  EXPECT_FALSE(par.rejected.empty());
}

}  // namespace
}  // namespace csgtile::fit
