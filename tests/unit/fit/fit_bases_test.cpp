// One ground per building (geo/fit/src/bases.cpp): touching vertical extrusions whose bases
// lie within the tolerance stand on the lowest; tops, clipped roofs and far parts stay.

#include <gtest/gtest.h>

#include <vector>

#include "csgtile/kernel/primitives.h"
#include "fit_internal.h"

namespace csgtile::fit {
namespace {

using kernel::Vec2;
using kernel::Vec3;

geo::ScenePrimitive square(double x, double y, double base, double height) {
  geo::ScenePrimitive p;
  p.spec.type = kernel::PrimitiveType::Extrusion;
  p.spec.profile = {Vec2(-1, -1), Vec2(1, -1), Vec2(1, 1), Vec2(-1, 1)};
  p.spec.height = height;
  p.spec.placement =
      kernel::Location::from_parts(Eigen::Matrix3d::Identity(), 1.0, Vec3(x, y, base)).value();
  return p;
}

double base_of(const geo::ScenePrimitive& p) { return p.spec.placement.translation().z(); }
double top_of(const geo::ScenePrimitive& p) { return base_of(p) + p.spec.height; }

TEST(FitBases, TouchingPartsWithinTheToleranceShareTheLowestBase) {
  std::vector<geo::ScenePrimitive> parts = {square(0, 0, 0.012, 5.0), square(2, 0, 0.004, 7.0),
                                            square(4, 0, 0.030, 3.0),  // touches the second
                                            square(2, 0, 1.5, 2.0),    // a step of its own
                                            square(50, 0, 0.0, 4.0)};  // another building
  // A roof clip of the first part, 4.5 m above its base (a half-space of its local frame).
  parts[0].spec.clips.push_back(Eigen::Vector4d(0, 0, 1, 4.5));
  const double clip_world = base_of(parts[0]) + 4.5;
  const auto before = parts;
  EXPECT_EQ(detail::snap_extrusion_bases(parts, 0.3), 2u);
  EXPECT_DOUBLE_EQ(base_of(parts[0]), 0.004);
  EXPECT_DOUBLE_EQ(base_of(parts[1]), 0.004);
  EXPECT_DOUBLE_EQ(base_of(parts[2]), 0.004);
  for (std::size_t i = 0; i < parts.size(); ++i) {
    EXPECT_NEAR(top_of(parts[i]), top_of(before[i]), 1e-12) << i;
  }
  EXPECT_DOUBLE_EQ(base_of(parts[3]), 1.5);
  EXPECT_DOUBLE_EQ(base_of(parts[4]), 0.0);
  EXPECT_NEAR(base_of(parts[0]) + parts[0].spec.clips[0].w(), clip_world, 1e-12);
  // The same parts give the same result (deterministic), and a zero tolerance moves nothing.
  auto again = before;
  detail::snap_extrusion_bases(again, 0.3);
  for (std::size_t i = 0; i < parts.size(); ++i) EXPECT_EQ(base_of(again[i]), base_of(parts[i]));
  auto untouched = before;
  EXPECT_EQ(detail::snap_extrusion_bases(untouched, 0.0), 0u);
}

}  // namespace
}  // namespace csgtile::fit
