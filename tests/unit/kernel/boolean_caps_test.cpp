// Caps standing on a planar face: a clipped sphere (or a coaxial cylinder) whose base disc lies
// inside a larger planar face of the other solid. The disc's circle is an edge of both solids'
// faces; the fuse must take it as one section and close both faces along it.

#include <gtest/gtest.h>

#include <numbers>
#include <tuple>

#include "csgtile/kernel/boolean.h"
#include "csgtile/kernel/check.h"
#include "csgtile/kernel/mass_properties.h"
#include "csgtile/kernel/primitives.h"
#include "model_builders.h"

namespace csgtile::kernel {
namespace {

double volume(const Shape& s) { return mass_properties(s).volume; }

Shape valid(const Result<Shape>& r, const std::string& what) { return test::valid_solid(r, what); }

// A sphere of radius r centred at `centre`, cut to z >= centre.z + base (base in (-r, r)).
Shape cap(double r, const Vec3& centre, double base) {
  PrimitiveSpec s;
  s.type = PrimitiveType::Sphere;
  s.radius = r;
  s.clips = {Eigen::Vector4d(0, 0, -1, -base)};
  s.placement = Location::translation(centre);
  return build_primitive(s).value();
}

double cap_volume(double r, double base) {
  const double h = r - base;  // height of the cap above its base
  return std::numbers::pi * h * h * (3 * r - h) / 3;
}

TEST(BooleanCaps, HemisphereOnABoxTop) {
  const Shape box = make_box(20, 20, 8).value();
  for (const double base : {0.0, 1.0, -1.5}) {
    SCOPED_TRACE("base " + std::to_string(base));
    const double r = 3;
    const Shape dome = cap(r, Vec3(10, 10, 8 - base), base);
    const Shape fused = valid(boolean_operation(box, dome, BooleanOp::Fuse), "fuse");
    if (fused.is_null()) continue;
    EXPECT_NEAR(volume(fused), 20 * 20 * 8 + cap_volume(r, base), 1e-9 * 4000);
  }
}

TEST(BooleanCaps, CylinderOnABoxTop) {
  const Shape box = make_box(20, 20, 8).value();
  const Shape column = make_cylinder(3, 4).value().moved(Location::translation(Vec3(10, 10, 8)));
  const Shape fused = valid(boolean_operation(box, column, BooleanOp::Fuse), "fuse");
  if (!fused.is_null()) {
    EXPECT_NEAR(volume(fused), 20 * 20 * 8 + std::numbers::pi * 9 * 4, 1e-9 * 4000);
  }
}

// The dome on its drum, the drum standing on the box: both the drum's base and the cap's base
// are circles of the box's top face or of each other.
TEST(BooleanCaps, DomeOnADrumOnABox) {
  const Shape box = make_box(20, 20, 8).value();
  const Shape drum = make_cylinder(3, 2).value().moved(Location::translation(Vec3(10, 10, 8)));
  const Shape dome = cap(3, Vec3(10, 10, 10), 0.0);
  const Shape fused = valid(boolean_fuse_all({box, drum, dome}), "fuse_all");
  if (!fused.is_null()) {
    EXPECT_NEAR(volume(fused), 20 * 20 * 8 + std::numbers::pi * 9 * 2 + cap_volume(3, 0),
                1e-9 * 4000);
  }
}

TEST(BooleanCaps, HemisphereInsideAWiderColumnTop) {
  const Shape column = make_cylinder(6, 8).value();
  const Shape dome = cap(3, Vec3(0, 0, 8), 0.0);
  const Shape fused = valid(boolean_operation(column, dome, BooleanOp::Fuse), "fuse");
  if (!fused.is_null()) {
    EXPECT_NEAR(volume(fused), std::numbers::pi * 36 * 8 + cap_volume(3, 0), 1e-9 * 4000);
  }
}

// A cap sunk into the box (its base 1.5 below the top face, the sphere's centre on it), in a
// turned and shifted placement: the three operations against the volumes in closed form.
TEST(BooleanCaps, SunkCapAllOperations) {
  const double r = 3, pi = std::numbers::pi;
  const Location at = Location::translation(Vec3(-40, 17, 3)) *
                      Location::rotation(Vec3::Zero(), Vec3(1, 2, 3).normalized(), 0.7);
  const Shape box = make_box(20, 20, 8).value().moved(at);
  const Shape sunk = cap(r, Vec3(10, 10, 8), -1.5).moved(at);
  const double hemisphere = 2.0 / 3.0 * pi * r * r * r;
  const double below = cap_volume(r, -1.5) - hemisphere;  // the slab between 6.5 and 8
  const std::tuple<BooleanOp, double> expected[] = {{BooleanOp::Fuse, 3200 + hemisphere},
                                                    {BooleanOp::Common, below},
                                                    {BooleanOp::Cut, 3200 - below}};
  for (const auto& [op, want] : expected) {
    const Shape result = valid(boolean_operation(box, sunk, op), boolean_op_name(op));
    if (!result.is_null()) {
      EXPECT_NEAR(volume(result), want, 1e-9 * 3200) << boolean_op_name(op);
    }
  }
}

// A zone of a sphere (cut by two parallel planes: two rims, no pole; one loop of four uses as
// well) standing on the box's top.
TEST(BooleanCaps, SphereZoneOnABoxTop) {
  const Shape box = make_box(20, 20, 8).value();
  PrimitiveSpec s;
  s.type = PrimitiveType::Sphere;
  s.radius = 3;
  s.clips = {Eigen::Vector4d(0, 0, -1, 1), Eigen::Vector4d(0, 0, 1, 2)};  // -1 <= z <= 2
  s.placement = Location::translation(Vec3(10, 10, 9));
  const Shape zone = build_primitive(s).value();
  const double want = 3200 + cap_volume(3, -1) - cap_volume(3, 2);
  const Shape fused = valid(boolean_operation(box, zone, BooleanOp::Fuse), "fuse");
  if (!fused.is_null()) {
    EXPECT_NEAR(volume(fused), want, 1e-9 * want);
  }
}

}  // namespace
}  // namespace csgtile::kernel
