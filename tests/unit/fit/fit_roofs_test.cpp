// Buildings seen from the air (issue #6, defects found on real AHN tiles): a flat roof with
// AHN-like noise reaches the terrain instead of becoming a slab a few centimetres thick; a
// gable (two roof planes meeting at a ridge) and a shed roof (one tilted plane) each become one
// extrusion down to the terrain; on sloping terrain a building reaches the foot of the slope
// around it; a box never reaches below the terrain; coaxial overlapping cones make one
// primitive.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "csgtile/fit/fit.h"
#include "csgtile/kernel/mass_properties.h"
#include "fit_clouds.h"
#include "fit_internal.h"
#include "proposal_input.h"

namespace csgtile::fit {
namespace {

using kernel::PrimitiveType;
using kernel::Vec2;
using kernel::Vec3;
using testing::Cloud;
using testing::fit_airborne;
using testing::flat_ground;

RansacOptions airborne_ransac() {
  RansacOptions o;
  o.epsilon = 0.02;  // the fit's default, as on the real tiles
  o.min_points = 40;
  o.seed = 3;
  return o;
}

std::string describe(const FittedPrimitives& f) {
  std::string s;
  for (const auto& p : f.primitives) {
    s += std::string(kernel::primitive_type_name(p.spec.type)) +
         (p.spec.clips.empty() ? "" : "(clipped)") + " ";
  }
  for (const auto& r : f.rejected) s += "| " + r.what + ": " + r.reason + " ";
  return s;
}

// Lowest and highest world z of a box or extrusion.
std::pair<double, double> z_range(const kernel::PrimitiveSpec& s) {
  std::vector<Vec3> corners;
  if (s.type == PrimitiveType::Box) {
    for (int k = 0; k < 8; ++k) {
      corners.emplace_back((k & 1) ? s.size.x() : 0.0, (k & 2) ? s.size.y() : 0.0,
                           (k & 4) ? s.size.z() : 0.0);
    }
  } else {
    for (const Vec2& v : s.profile) {
      corners.emplace_back(v.x(), v.y(), 0.0);
      corners.emplace_back(v.x(), v.y(), s.height);
    }
  }
  double lo = INFINITY, hi = -INFINITY;
  for (const auto& c : corners) {
    const double z = s.placement.apply_point(c).z();
    lo = std::min(lo, z);
    hi = std::max(hi, z);
  }
  return {lo, hi};
}

// Whether a box or an unclipped extrusion holds the world point `q`.
bool holds(const kernel::PrimitiveSpec& s, const Vec3& q) {
  const Vec3 l = s.placement.inverse().apply_point(q);
  if (s.type == PrimitiveType::Box) {
    return l.x() >= 0 && l.y() >= 0 && l.z() >= 0 && l.x() <= s.size.x() && l.y() <= s.size.y() &&
           l.z() <= s.size.z();
  }
  if (s.type != PrimitiveType::Extrusion || l.z() < 0 || l.z() > s.height) return false;
  bool in = false;  // even-odd over the outer ring
  for (std::size_t i = 0, j = s.profile.size() - 1; i < s.profile.size(); j = i++) {
    const Vec2 &a = s.profile[i], &b = s.profile[j];
    if ((a.y() > l.y()) != (b.y() > l.y()) &&
        l.x() < a.x() + (l.y() - a.y()) * (b.x() - a.x()) / (b.y() - a.y())) {
      in = !in;
    }
  }
  return in;
}

// A roof surface seen from the air: points uniform (10 per m²) over the parallelogram
// corner + [0,1]·e1 + [0,1]·e2, with Gaussian noise σ along its normal.
Cloud roof(const Vec3& corner, const Vec3& e1, const Vec3& e2, double sigma, std::uint64_t seed) {
  return testing::rectangle_cloud(corner, e1, e2, std::sqrt(0.1), sigma, seed);
}

TEST(FitRoofs, NoisyFlatRoofBecomesABuildingDownToTheGround) {
  // 15 × 12.5 m at 18 m, σ = 3 cm (AHN-like): before, a 5 cm slab at roof height.
  const GroundGrid ground = flat_ground();
  const Cloud c = roof(Vec3(0, 0, 18), Vec3(15, 0, 0), Vec3(0, 12.5, 0), 0.03, 11);
  const auto f = fit_airborne(c, ground);
  ASSERT_EQ(f.primitives.size(), 1U) << describe(f);
  const auto& p = f.primitives[0].spec;
  ASSERT_EQ(p.type, PrimitiveType::Box) << describe(f);
  const auto [lo, hi] = z_range(p);
  EXPECT_NEAR(lo, 0.0, 0.1);
  EXPECT_NEAR(hi, 18.0, 0.1);
}

TEST(FitRoofs, RoofOnSlopingTerrainReachesTheFootOfTheSlopeNotBeyond) {
  // Terrain rising 0.2 m per m along x (level 0 at x = 0), a 12 × 8 m flat roof at z = 10
  // over x in [0, 12]: the building's bottom is the lowest terrain around its footprint
  // (about 0 at its low wall), not the lower ground several metres off (−1 m at x = −5).
  GroundGrid ground = flat_ground();
  for (int j = 0; j < ground.ny; ++j) {
    for (int i = 0; i < ground.nx; ++i) {
      const double level = 0.2 * (ground.x0 + (i + 0.5) * ground.cell);
      ground.mean[static_cast<std::size_t>(j * ground.nx + i)] = level;
      ground.z[static_cast<std::size_t>(j * ground.nx + i)] = level - 0.03;
    }
  }
  const Cloud c = roof(Vec3(0, 0, 10), Vec3(12, 0, 0), Vec3(0, 8, 0), 0.02, 12);
  const auto f = fit_airborne(c, ground);
  ASSERT_EQ(f.primitives.size(), 1U) << describe(f);
  const auto [lo, hi] = z_range(f.primitives[0].spec);
  EXPECT_GE(lo, -0.5);
  EXPECT_LE(lo, 0.1);
  EXPECT_NEAR(hi, 10.0, 0.1);
}

TEST(FitRoofs, GableRoofPairIsOneSolidDownToTheGround) {
  // 10 m along x; across y: eaves at y = 0 and 8 (z = 6), ridge at y = 4 (z = 8). No walls.
  const GroundGrid ground = flat_ground();
  Cloud c = roof(Vec3(0, 0, 6), Vec3(10, 0, 0), Vec3(0, 4, 2), 0.03, 1);
  c.append(roof(Vec3(0, 8, 6), Vec3(0, -4, 2), Vec3(10, 0, 0), 0.03, 2));
  const auto f = fit_airborne(c, ground);
  ASSERT_EQ(f.primitives.size(), 1U) << describe(f);
  const auto& p = f.primitives[0].spec;
  ASSERT_EQ(p.type, PrimitiveType::Extrusion) << describe(f);
  EXPECT_LT(testing::line_angle_deg(p.placement.rotation().col(2), Vec3::UnitX()), 1.0);
  EXPECT_NEAR(p.height, 10.0, 0.3);
  ASSERT_EQ(p.profile.size(), 5U);
  const auto [lo, hi] = z_range(p);
  EXPECT_NEAR(lo, 0.0, 0.1);
  EXPECT_NEAR(hi, 8.0, 0.1);
  // The ridge is a profile vertex (world y = 4, z = 8), the eaves at z = 6.
  double ridge = INFINITY;
  for (const auto& v : p.profile) {
    const Vec3 w = p.placement.apply_point(Vec3(v.x(), v.y(), 0.0));
    ridge = std::min(ridge, std::hypot(w.y() - 4.0, w.z() - 8.0));
  }
  EXPECT_LT(ridge, 0.15);
  // Every roof point is explained.
  EXPECT_GE(f.assigned_points, static_cast<long long>(0.95 * static_cast<double>(c.points.size())));
  // Deterministic.
  const auto again = fit_airborne(c, ground);
  ASSERT_EQ(again.primitives.size(), 1U);
  EXPECT_EQ(again.primitives[0].spec.profile, p.profile);
}

TEST(FitRoofs, ShedRoofIsOneSolidDownToTheGround) {
  // One plane, 9 m along x, rising from z = 4 at y = 0 to z = 6 at y = 5.
  const GroundGrid ground = flat_ground();
  const Cloud c = roof(Vec3(0, 0, 4), Vec3(9, 0, 0), Vec3(0, 5, 2), 0.02, 5);
  const auto f = fit_airborne(c, ground);
  ASSERT_EQ(f.primitives.size(), 1U) << describe(f);
  const auto& p = f.primitives[0].spec;
  ASSERT_EQ(p.type, PrimitiveType::Extrusion) << describe(f);
  EXPECT_EQ(p.profile.size(), 4U);
  const auto [lo, hi] = z_range(p);
  EXPECT_NEAR(lo, 0.0, 0.1);
  EXPECT_NEAR(hi, 6.0, 0.1);
}

TEST(FitRoofs, TiltedPlaneNearTheGroundIsNoBuilding) {
  // A ramp from z = 0.3 to 1.3 (eaves under 1 m): no extrusion, and the reason says why.
  const GroundGrid ground = flat_ground();
  const Cloud c = roof(Vec3(0, 0, 0.3), Vec3(9, 0, 0), Vec3(0, 5, 1), 0.01, 6);
  const auto f = fit_airborne(c, ground);
  for (const auto& p : f.primitives) EXPECT_NE(p.spec.type, PrimitiveType::Extrusion);
  bool named = false;
  for (const auto& r : f.rejected) named = named || r.reason.find("eaves") != std::string::npos;
  EXPECT_TRUE(named) << describe(f);
}

TEST(FitRoofs, BoxNeverReachesBelowTheTerrain) {
  // A roof plane tilted 30° (z 4..7) and, 6 m behind it along its normal, points parallel to
  // it above the terrain (the far side of a building): taken as the box's opposite face, the
  // box would reach 1.2 m into the ground. Extrusions off: the box code alone.
  const GroundGrid ground = flat_ground();
  const double a = std::numbers::pi / 6.0;
  const Vec3 along(8, 0, 0), up_slope(0, 6 * std::cos(a), 6 * std::sin(a));
  const Vec3 n = along.cross(up_slope).normalized();  // points up and back
  Cloud c = roof(Vec3(0, 0, 4), along, up_slope, 0.005, 7);
  Cloud far = roof(Vec3(0, 0, 4) - 6.0 * n, along, up_slope, 0.005, 8);
  for (std::size_t i = 0; i < far.points.size(); ++i) {
    if (far.points[i].z() < 0.3) continue;
    c.points.push_back(far.points[i]);
    c.normals.push_back(far.normals[i]);
  }
  const auto f = fit_airborne(c, ground, {.extrusions = false});
  for (const auto& p : f.primitives) {
    EXPECT_GE(z_range(p.spec).first, -0.25) << describe(f);
  }
}

// A flat canopy 6 x 6 m at 3 m on five posts, the posts scanned all round (a terrestrial
// scan of a frame's bays): the canopy's outline down to the terrain would be a block holding
// the posts. Points measured deep inside a solid contradict it: no box or extrusion may hold
// the posts' points, and the refusal is named.
TEST(FitRoofs, NoBlockHoldsThePostsUnderACanopy) {
  const GroundGrid ground = flat_ground();
  Cloud c = testing::rectangle_cloud(Vec3(0, 0, 3), Vec3(6, 0, 0), Vec3(0, 6, 0), 0.05, 0.002, 4);
  std::uint64_t seed = 40;
  const std::vector<Vec2> posts{{0.5, 0.5}, {5.5, 0.5}, {0.5, 5.5}, {5.5, 5.5}, {3.0, 3.0}};
  for (const Vec2& q : posts) {
    c.append(testing::cylinder_cloud(Vec3(q.x(), q.y(), 0.0), Vec3::UnitZ(), 0.15, 2.95, 0.0,
                                     2.0 * std::numbers::pi, 3000, 0.002, seed++));
  }
  const auto f = fit_airborne(c, ground);
  int posts_found = 0;
  for (const auto& p : f.primitives) {
    if (p.spec.type == PrimitiveType::Cylinder) {
      ++posts_found;
      continue;
    }
    for (const Vec2& q : posts) {
      EXPECT_FALSE(holds(p.spec, Vec3(q.x(), q.y(), 1.5))) << describe(f);
    }
  }
  EXPECT_EQ(posts_found, 5) << describe(f);
  EXPECT_NE(describe(f).find("lie deep inside it"), std::string::npos) << describe(f);
}

TEST(FitRoofs, CoaxialOverlappingConesMakeOnePrimitive) {
  // A round tower whose roof the RANSAC split into two cones on one axis, overlapping along
  // it (shapes given directly): the earlier, larger one is kept.
  const Vec3 apex(2, 3, 12), axis(0, 0, -1);
  const double half = std::atan(0.5);
  Cloud c = testing::cone_cloud(apex, axis, half, 0.5, 3.0, 3000, 0.002, 1);
  const std::size_t first = c.points.size();
  c.append(testing::cone_cloud(apex + Vec3(0.01, 0, 0), axis, half, 1.5, 2.5, 1000, 0.002, 2));
  RansacResult shapes;
  shapes.cluster_epsilon = 0.1;
  shapes.assignment.assign(c.points.size(), 0);
  DetectedShape big, small;
  big.surface.type = small.surface.type = ShapeType::Cone;
  big.surface.point = apex;
  small.surface.point = apex + Vec3(0.01, 0, 0);
  big.surface.axis = small.surface.axis = axis;
  big.surface.angle = small.surface.angle = half;
  for (std::uint32_t i = 0; i < c.points.size(); ++i) {
    (i < first ? big : small).inliers.push_back(i);
    if (i >= first) shapes.assignment[i] = 1;
  }
  shapes.shapes = {big, small};
  const RansacOptions o = airborne_ransac();
  const auto f = primitives_from_shapes(c.points, c.normals, shapes, PrimitiveOptions{}, o, 0);
  ASSERT_EQ(f.primitives.size(), 1U) << describe(f);
  EXPECT_EQ(f.primitives[0].spec.type, PrimitiveType::Cone);
  EXPECT_NEAR(f.primitives[0].spec.height, 2.5, 0.05);
  bool named = false;
  for (const auto& r : f.rejected) named = named || r.reason.find("coaxial") != std::string::npos;
  EXPECT_TRUE(named) << describe(f);
}

// A shed roof (z = 6 + 0.3 y) over an L-shaped outline, seen from the air: its roof part
// (roof_parts.cpp, the step after the pitched roofs) is the extrusion of the L from the
// terrain, clipped by the roof plane — no roof over the L's empty corner.
TEST(FitRoofs, RoofPartOfAShedOverAnLIsTheClippedExtrusionOfTheL) {
  const GroundGrid ground = flat_ground();
  const Vec3 slope(0.0, 1.0, 0.3);
  Cloud c = roof(Vec3(0.0, 0.0, 6.0), Vec3(12.0, 0.0, 0.0), 5.0 * slope, 0.01, 21);
  c.append(roof(Vec3(0.0, 0.0, 6.0) + 5.0 * slope, Vec3(5.0, 0.0, 0.0), 7.0 * slope, 0.01, 22));
  const RansacOptions o = airborne_ransac();
  auto shapes = detect_shapes(c.points, c.normals, o);
  ASSERT_TRUE(shapes.ok());
  PrimitiveOptions options;
  options.ground = &ground;
  const testing::FreshProposalInput fresh(c, shapes.value(), options, o);
  std::vector<Rejection> rejected;
  const auto parts = detail::propose_roof_parts(fresh.in, rejected);
  ASSERT_FALSE(parts.empty());
  const kernel::PrimitiveSpec& s = parts[0].spec;  // the largest plane: the whole roof
  ASSERT_EQ(s.type, PrimitiveType::Extrusion);
  ASSERT_EQ(s.clips.size(), 1u);
  const auto solid = kernel::build_primitive(s);
  ASSERT_TRUE(solid.ok()) << solid.error().message;
  // Volume of the L under the roof: [0,12]×[0,5] at mean 6.75, [0,5]×[5,12] at mean 8.55,
  // within the outline's precision (1.5 × the spacing along the edges); a roof over the
  // empty corner would add 49 m² × 9.5 m, 63 %.
  const double expected = 60.0 * 6.75 + 35.0 * 8.55;
  EXPECT_NEAR(kernel::mass_properties(solid.value()).volume, expected, 0.08 * expected);
  const kernel::BoundingBox box = kernel::bounding_box(solid.value());
  EXPECT_NEAR(box.max.z(), 6.0 + 0.3 * 12.0, 0.15);
  EXPECT_NEAR(box.min.z(), 0.0, 0.1);
}

}  // namespace
}  // namespace csgtile::fit
