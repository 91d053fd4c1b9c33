// Scene primitives between length units (geo/scene_units.h): the fit measures in metres and
// gives its primitives back in the tile's units, feet included.

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "csgtile/geo/scene_units.h"
#include "csgtile/kernel/explorer.h"
#include "csgtile/kernel/mass_properties.h"
#include "model_builders.h"

namespace csgtile {
namespace {

using kernel::Location;
using kernel::PrimitiveSpec;
using kernel::PrimitiveType;
using kernel::Vec2;
using kernel::Vec3;

constexpr double kFoot = 0.3048;

double volume_of(const PrimitiveSpec& spec) {
  auto solid = kernel::build_primitive(spec);
  EXPECT_TRUE(solid.ok()) << (solid.ok() ? "" : solid.error().message);
  return solid.ok() ? kernel::shape_volume(solid.value()) : NAN;
}

Vec3 lowest_corner(const PrimitiveSpec& spec) {
  auto solid = kernel::build_primitive(spec);
  EXPECT_TRUE(solid.ok());
  Vec3 lo = Vec3::Constant(INFINITY);
  for (const kernel::Shape& v : kernel::Explorer(solid.value(), kernel::ShapeKind::Vertex)) {
    lo = lo.cwiseMin(kernel::vertex_point(v));
  }
  return lo;
}

geo::ScenePrimitive scene(PrimitiveSpec spec) {
  geo::ScenePrimitive p;
  p.spec = std::move(spec);
  p.id = "r0-0";
  p.quality = geo::FitQuality{120, 0.02, 0.8, 0.01, 0.95};
  return p;
}

// A rotation by `angle` about z, then a move to `t`.
Location about_z(double angle, const Vec3& t) {
  return Location::translation(t) * Location::rotation(Vec3::Zero(), Vec3::UnitZ(), angle);
}

TEST(SceneUnits, MetresToFeetScalesEveryTypeByTheCube) {
  const double s = 1.0 / kFoot;  // metres to feet
  const Location tilted = Location::translation({3.0, -2.0, 5.0}) *
                          Location::rotation(Vec3::Zero(), Vec3(1.0, 2.0, 0.5), 0.7);
  PrimitiveSpec sphere;
  sphere.type = PrimitiveType::Sphere;
  sphere.radius = 1.5;
  sphere.placement = tilted;
  PrimitiveSpec torus;
  torus.type = PrimitiveType::Torus;
  torus.radius = 2.0;
  torus.radius2 = 0.5;
  torus.placement = tilted;
  PrimitiveSpec cone;
  cone.type = PrimitiveType::Cone;
  cone.radius = 1.0;
  cone.radius2 = 0.4;
  cone.height = 3.0;
  cone.placement = tilted;
  PrimitiveSpec revolution;
  revolution.type = PrimitiveType::Revolution;
  revolution.profile = {{0.0, 0.0}, {2.0, 0.0}, {1.0, 1.5}, {0.0, 1.5}};
  revolution.angle = 2.0 * std::numbers::pi;
  revolution.placement = tilted;
  for (const PrimitiveSpec& spec :
       {test::box({2.0, 3.0, 4.0}, tilted), test::cylinder(0.5, 6.0, tilted), sphere, torus, cone,
        revolution, test::gable_house()}) {
    SCOPED_TRACE(kernel::primitive_type_name(spec.type));
    auto scaled = geo::scaled_primitive(scene(spec), {s, s});
    ASSERT_TRUE(scaled.ok()) << scaled.error().message;
    EXPECT_NEAR(volume_of(scaled.value().spec), volume_of(spec) * s * s * s,
                1e-9 * volume_of(spec) * s * s * s);
    EXPECT_LT((lowest_corner(scaled.value().spec) - s * lowest_corner(spec)).norm(), 1e-6);
    EXPECT_NEAR(scaled.value().quality->rms, 0.02 * s, 1e-15);
    EXPECT_NEAR(*scaled.value().quality->sigma, 0.01 * s, 1e-15);
    EXPECT_EQ(scaled.value().quality->inliers, 120);
    // And back, to rounding.
    auto back = geo::scaled_primitive(scaled.value(), geo::UnitScale{s, s}.inverse());
    ASSERT_TRUE(back.ok());
    EXPECT_NEAR(volume_of(back.value().spec), volume_of(spec), 1e-9 * volume_of(spec));
  }
}

TEST(SceneUnits, HeightsInAnotherUnitKeepBuildingsExact) {
  // Horizontal coordinates in metres, heights in feet: diag(1, 1, 1/0.3048). A gable house
  // rotated about z (an extrusion cut by its roof planes), a box and a column keep their form:
  // their volumes scale by the heights' factor, their ridge goes to its height in feet.
  const geo::UnitScale to_feet_heights{1.0, 1.0 / kFoot};
  PrimitiveSpec house = test::gable_house();
  house.placement = about_z(0.4, {100.0, 200.0, 3.0});
  const Location turned = about_z(-1.1, {5.0, 6.0, 2.0});
  for (const PrimitiveSpec& spec :
       {house, test::box({2.0, 3.0, 4.0}, turned), test::cylinder(0.5, 6.0, turned)}) {
    SCOPED_TRACE(kernel::primitive_type_name(spec.type));
    auto scaled = geo::scaled_primitive(scene(spec), to_feet_heights);
    ASSERT_TRUE(scaled.ok()) << scaled.error().message;
    EXPECT_NEAR(volume_of(scaled.value().spec), volume_of(spec) / kFoot,
                1e-9 * volume_of(spec) / kFoot);
    const Vec3 lo = lowest_corner(spec), lo_scaled = lowest_corner(scaled.value().spec);
    EXPECT_LT((lo_scaled - Vec3(lo.x(), lo.y(), lo.z() / kFoot)).norm(), 1e-6);
  }
  auto ridge = [](const PrimitiveSpec& spec) {
    auto solid = kernel::build_primitive(spec);
    double top = -INFINITY;
    for (const kernel::Shape& v : kernel::Explorer(solid.value(), kernel::ShapeKind::Vertex)) {
      top = std::max(top, kernel::vertex_point(v).z());
    }
    return top;
  };
  auto scaled = geo::scaled_primitive(scene(house), to_feet_heights);
  ASSERT_TRUE(scaled.ok());
  EXPECT_NEAR(ridge(scaled.value().spec), (3.0 + 8.0) / kFoot, 1e-9);
}

TEST(SceneUnits, HeightsInAnotherUnitRefuseWhatWouldBecomeAnEllipsoid) {
  const geo::UnitScale mixed{1.0, 1.0 / kFoot};
  PrimitiveSpec sphere;
  sphere.type = PrimitiveType::Sphere;
  sphere.radius = 1.0;
  auto refused = geo::scaled_primitive(scene(sphere), mixed);
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.error().code, kernel::ErrorCode::Unsupported);
  EXPECT_NE(refused.error().message.find("sphere r0-0"), std::string::npos)
      << refused.error().message;
  // A beam along x: its local z leaves the vertical.
  const Location lying = Location::rotation(Vec3::Zero(), Vec3::UnitY(), std::numbers::pi / 2);
  auto tilted = geo::scaled_primitive(scene(test::cylinder(0.1, 3.0, lying)), mixed);
  ASSERT_FALSE(tilted.ok());
  EXPECT_NE(tilted.error().message.find("tilted"), std::string::npos);
  // The same are exact under one unit for all three axes.
  EXPECT_TRUE(geo::scaled_primitive(scene(sphere), {2.0, 2.0}).ok());
  EXPECT_FALSE(geo::scaled_primitive(scene(sphere), {0.0, 1.0}).ok());
  EXPECT_FALSE(geo::scaled_primitive(scene(sphere), {1.0, NAN}).ok());
}

}  // namespace
}  // namespace csgtile
