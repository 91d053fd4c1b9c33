// From detected shapes to scene primitives: a beam seen from three sides is one box with its
// size and placement, curved shapes are bounded by their inliers, every primitive is a valid
// kernel solid with its fit quality.

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "csgtile/geo/fit.h"
#include "csgtile/geo/segment.h"
#include "csgtile/kernel/check.h"
#include "fit_clouds.h"

namespace csgtile::geo {
namespace {

using kernel::PrimitiveType;
using kernel::Vec3;
using testing::Cloud;

struct Fitted {
  RansacResult shapes;
  FittedPrimitives primitives;
};

Fitted fit(const Cloud& c, double epsilon = 0.01) {
  RansacOptions o;
  o.epsilon = epsilon;
  o.min_points = 50;
  o.seed = 3;
  const auto normals = estimate_normals(c.points, {});
  auto shapes = detect_shapes(c.points, normals, o);
  EXPECT_TRUE(shapes.ok());
  Fitted f;
  f.shapes = shapes.value();
  f.primitives = primitives_from_shapes(c.points, normals, f.shapes, PrimitiveOptions{}, o, 0);
  return f;
}

Vec3 box_centre(const kernel::PrimitiveSpec& s) { return s.placement.apply_point(0.5 * s.size); }

TEST(FitPrimitives, BeamSeenFromThreeSidesIsOneBox) {
  // A 3 × 0.2 × 0.3 beam turned 30° about z, scanned on its two long sides and its bottom.
  const double turn = 30.0 * std::numbers::pi / 180.0;
  const Vec3 ex(std::cos(turn), std::sin(turn), 0.0), ey(-std::sin(turn), std::cos(turn), 0.0);
  const Vec3 ez = Vec3::UnitZ();
  const Vec3 corner(2.0, -1.0, 3.7);
  const Vec3 lx = 3.0 * ex, ly = 0.2 * ey, lz = 0.3 * ez;
  Cloud c = testing::rectangle_cloud(corner, lz, lx, 0.01, 0.002, 1);       // y = 0 side
  c.append(testing::rectangle_cloud(corner + ly, lx, lz, 0.01, 0.002, 2));  // y = 0.2 side
  c.append(testing::rectangle_cloud(corner, lx, ly, 0.01, 0.002, 3));       // bottom
  const Fitted f = fit(c);
  ASSERT_EQ(f.primitives.primitives.size(), 1U);
  const auto& p = f.primitives.primitives[0];
  ASSERT_EQ(p.spec.type, PrimitiveType::Box);
  const Vec3 expected_centre = corner + 0.5 * (lx + ly + lz);
  EXPECT_LT((box_centre(p.spec) - expected_centre).norm(), 0.02);
  std::vector<double> size{p.spec.size.x(), p.spec.size.y(), p.spec.size.z()};
  std::sort(size.begin(), size.end());
  EXPECT_NEAR(size[0], 0.2, 0.02);
  EXPECT_NEAR(size[1], 0.3, 0.02);
  EXPECT_NEAR(size[2], 3.0, 0.02);
  // The long edge runs along the beam.
  Vec3 long_axis = p.spec.placement.rotation().col(0);
  if (p.spec.size.y() > p.spec.size.x() && p.spec.size.y() > p.spec.size.z()) {
    long_axis = p.spec.placement.rotation().col(1);
  } else if (p.spec.size.z() > p.spec.size.x()) {
    long_axis = p.spec.placement.rotation().col(2);
  }
  EXPECT_LT(testing::line_angle_deg(long_axis, ex), 1.0);
  ASSERT_TRUE(p.quality.has_value());
  EXPECT_GT(p.quality->inliers,
            static_cast<long long>(0.95 * static_cast<double>(c.points.size())));
  EXPECT_LT(p.quality->rms, 0.005);
  EXPECT_GT(p.quality->coverage, 0.3);
  EXPECT_EQ(p.id, "r0-0");
}

TEST(FitPrimitives, CylinderIsBoundedByItsInliers) {
  const Cloud c = testing::cylinder_cloud(Vec3(1, 1, 0), Vec3::UnitZ(), 0.15, 3.7, 0.0,
                                          2.0 * std::numbers::pi, 5000, 0.003, 4);
  const Fitted f = fit(c);
  ASSERT_EQ(f.primitives.primitives.size(), 1U);
  const auto& p = f.primitives.primitives[0].spec;
  ASSERT_EQ(p.type, PrimitiveType::Cylinder);
  EXPECT_NEAR(p.radius, 0.15, 0.005);
  EXPECT_NEAR(p.height, 3.7, 0.03);
  const Vec3 base = p.placement.translation();
  const Vec3 top = p.placement.apply_point(Vec3(0, 0, p.height));
  EXPECT_LT((Vec3(base.x(), base.y(), 0) - Vec3(1, 1, 0)).norm(), 0.005);
  EXPECT_NEAR(std::min(base.z(), top.z()), 0.0, 0.02);
  EXPECT_TRUE(kernel::check_shape(kernel::build_primitive(p).value()).valid());
}

TEST(FitPrimitives, ConeSphereAndTorusBecomeValidSolids) {
  // Similar densities (the connectivity size follows the cloud's typical spacing).
  Cloud c = testing::cone_cloud(Vec3(0, 0, 2), Vec3(0, 0, -1), std::atan(1.2 / 2.0), 0.3, 2.0, 8000,
                                0.003, 5);
  c.append(testing::sphere_cloud(Vec3(20, 0, 8), 2.0, 0.0, 10000, 0.003, 6));
  c.append(testing::torus_cloud(Vec3(-20, 0, 3.45), Vec3::UnitY(), 2.5, 0.35, 15000, 0.003, 7));
  const Fitted f = fit(c);
  EXPECT_EQ(f.primitives.per_type[static_cast<int>(PrimitiveType::Cone)], 1);
  EXPECT_EQ(f.primitives.per_type[static_cast<int>(PrimitiveType::Sphere)], 1);
  EXPECT_EQ(f.primitives.per_type[static_cast<int>(PrimitiveType::Torus)], 1);
  for (const auto& p : f.primitives.primitives) {
    auto solid = kernel::build_primitive(p.spec);
    ASSERT_TRUE(solid.ok());
    EXPECT_TRUE(kernel::check_shape(solid.value()).valid());
    if (p.spec.type == PrimitiveType::Cone) {
      // Radius 1.2 at the base (z = 0), apex at z = 2: the inliers reach from t = 0.3 to 2.
      EXPECT_NEAR(std::max(p.spec.radius, p.spec.radius2), 1.2, 0.02);
      EXPECT_NEAR(p.spec.height, 1.7, 0.03);
    }
    if (p.spec.type == PrimitiveType::Sphere) {
      EXPECT_NEAR(p.spec.radius, 2.0, 0.005);
    }
    if (p.spec.type == PrimitiveType::Torus) {
      EXPECT_NEAR(p.spec.radius, 2.5, 0.01);
      EXPECT_NEAR(p.spec.radius2, 0.35, 0.005);
    }
  }
}

TEST(FitPrimitives, LonePlaneIsRejectedWithAReason) {
  const Cloud c =
      testing::rectangle_cloud(Vec3(0, 0, 0), Vec3(2, 0, 0), Vec3(0, 2, 0), 0.02, 0.002, 8);
  const Fitted f = fit(c);
  EXPECT_TRUE(f.primitives.primitives.empty());
  ASSERT_FALSE(f.primitives.rejected.empty());
  EXPECT_NE(f.primitives.rejected[0].reason.find("no box"), std::string::npos);
}

}  // namespace
}  // namespace csgtile::geo
