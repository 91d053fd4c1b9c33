// The RMS distance of a primitive's points to its solid (model_distance.cpp): the fit quality
// published per building as the RMSE of its points to the model.

#include <gtest/gtest.h>

#include <cmath>

#include "fit_internal.h"
#include "model_builders.h"

namespace csgtile::fit::detail {
namespace {

using kernel::Vec3;

kernel::Shape built(const kernel::PrimitiveSpec& spec) {
  auto s = kernel::build_primitive(spec);
  EXPECT_TRUE(s.ok()) << s.error().message;
  return s.value();
}

std::optional<BoundaryFit> measured(const kernel::Shape& solid, const std::vector<Vec3>& points,
                                    double near, double chordal = 0.001) {
  std::vector<std::uint32_t> members(points.size());
  for (std::uint32_t i = 0; i < members.size(); ++i) members[i] = i;
  return boundary_fit(solid, points, members, chordal, near);
}

std::optional<double> rms(const kernel::Shape& solid, const std::vector<Vec3>& points,
                          double chordal = 0.001) {
  const auto fit = measured(solid, points, 0.0, chordal);
  if (!fit) return std::nullopt;
  return fit->rms;
}

TEST(FitModelDistance, PointsInsideOnAndOutsideABox) {
  const kernel::Shape box = built(test::box_at({1, 2, 3}, {2, 3, 4}));
  EXPECT_NEAR(*rms(box, {{2, 3.5, 5}}), 1.0, 1e-12);  // the centre: 1 m from x faces
  EXPECT_NEAR(*rms(box, {{1, 3, 4}}), 0.0, 1e-12);    // on a face
  EXPECT_NEAR(*rms(box, {{3.1, 5.1, 7.1}}), std::sqrt(0.03), 1e-12);  // beyond a corner
  EXPECT_NEAR(*rms(box, {{2, 3.5, 5}, {1, 3, 4}}), std::sqrt(0.5), 1e-12);
}

TEST(FitModelDistance, CurvedSolidsWithinTheChordalTolerance) {
  const kernel::Shape cylinder = built(test::cylinder_at({0, 0, 0}, 1.0, 4.0));
  EXPECT_NEAR(*rms(cylinder, {{0, 0, 2}}), 1.0, 0.001);      // on the axis
  EXPECT_NEAR(*rms(cylinder, {{0.6, 0.8, 2}}), 0.0, 0.001);  // on the side
  EXPECT_NEAR(*rms(cylinder, {{0, 0, 4.5}}), 0.5, 1e-12);    // above the top disc
}

// A roof part: the gable house's points on its roof and eaves lie on the model; a point
// half a metre above the ridge is half a metre off.
TEST(FitModelDistance, ARoofPartMeasuresItsPointsToItsClippedSolid) {
  const kernel::Shape house = built(test::gable_house());
  EXPECT_NEAR(*rms(house, {{5, 1, 6}, {5, 3, 8}, {2, 5, 6}}), 0.0, 1e-9);
  EXPECT_NEAR(*rms(house, {{5, 3, 8.5}}), 0.5, 1e-9);
}

// The share near the model: of four points 0, 0.05, 0.1 and 1 m from a box's face, those
// within 2σ = 0.1 m (the bound included) are three.
TEST(FitModelDistance, ShareOfPointsWithinADistance) {
  const kernel::Shape box = built(test::box_at({0, 0, 0}, {10, 10, 10}));
  const std::vector<Vec3> points{{5, 5, 10}, {5, 5, 10.05}, {5, 5, 9.9}, {5, 5, 11}};
  const auto fit = measured(box, points, 2 * 0.05);
  ASSERT_TRUE(fit.has_value());
  EXPECT_DOUBLE_EQ(fit->share_near, 0.75);
  EXPECT_NEAR(fit->rms, std::sqrt((0.0025 + 0.01 + 1.0) / 4.0), 1e-12);
  EXPECT_DOUBLE_EQ(measured(box, points, 0.0)->share_near, 0.25);  // the point on the face
}

TEST(FitModelDistance, NothingToMeasure) {
  const kernel::Shape box = built(test::box_at({0, 0, 0}, {1, 1, 1}));
  EXPECT_FALSE(rms(box, {}).has_value());
  EXPECT_FALSE(rms(box, {{NAN, 0, 0}}).has_value());
}

}  // namespace
}  // namespace csgtile::fit::detail
