// merge_same_surface (geo/fit/src/shape_merge.h): shapes on one surface within a narrow gap
// of each other become one; a wider gap, another surface or another type keeps them apart; on
// exact points, so does a step far under epsilon that their own fits see.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "fit_internal.h"
#include "shape_merge.h"

namespace csgtile::fit {
namespace {

using kernel::Vec3;

// Points of z = `z` on a grid of step 0.4 over [x0, x1] × [0, 4], appended to `points`; the
// shape of those points (plane z = `z`).
DetectedShape patch(std::vector<Vec3>& points, double x0, double x1, double z) {
  DetectedShape s;
  s.surface.type = ShapeType::Plane;
  s.surface.point = Vec3(x0, 0.0, z);
  s.surface.axis = Vec3::UnitZ();
  for (double x = x0; x <= x1 + 1e-9; x += 0.4) {
    for (double y = 0.0; y <= 4.0 + 1e-9; y += 0.4) {
      s.inliers.push_back(static_cast<std::uint32_t>(points.size()));
      points.emplace_back(x, y, z);
    }
  }
  return s;
}

TEST(FitShapeMerge, ShapesOnOneSurfaceWithANarrowGapBecomeOne) {
  std::vector<Vec3> points;
  std::vector<DetectedShape> shapes;
  shapes.push_back(patch(points, 0.0, 4.0, 0.0));    // 0
  shapes.push_back(patch(points, 4.0, 8.0, 0.5));    // 1: another plane, touching 0 and 2
  shapes.push_back(patch(points, 4.6, 8.2, 0.0));    // 2: 0.6 from 0 (under 1.9 × 0.4)
  shapes.push_back(patch(points, 10.2, 12.2, 0.0));  // 3: 2.0 from 2: apart
  std::vector<int> assignment(points.size(), -1);
  for (std::size_t s = 0; s < shapes.size(); ++s) {
    for (auto i : shapes[s].inliers) assignment[i] = static_cast<int>(s);
  }
  const std::size_t sizes[4] = {shapes[0].inliers.size(), shapes[1].inliers.size(),
                                shapes[2].inliers.size(), shapes[3].inliers.size()};
  const double epsilon = 0.01;
  EXPECT_EQ(detail::merge_same_surface(points, shapes, assignment, epsilon), 1u);
  ASSERT_EQ(shapes.size(), 3u);
  EXPECT_EQ(shapes[0].inliers.size(), sizes[0] + sizes[2]);
  EXPECT_TRUE(std::is_sorted(shapes[0].inliers.begin(), shapes[0].inliers.end()));
  EXPECT_EQ(shapes[1].inliers.size(), sizes[1]);
  EXPECT_EQ(shapes[2].inliers.size(), sizes[3]);
  EXPECT_NEAR(std::abs(shapes[0].surface.axis.z()), 1.0, 1e-12);
  for (std::size_t s = 0; s < shapes.size(); ++s) {
    for (auto i : shapes[s].inliers) EXPECT_EQ(assignment[i], static_cast<int>(s));
  }
  // Once merged, nothing is left to merge.
  EXPECT_EQ(detail::merge_same_surface(points, shapes, assignment, epsilon), 0u);
}

// A spot face 0.006 below the face around it (within epsilon 0.01 of it): one surface for a
// noisy cloud, two where the points are exact (each patch fits its own plane to rounding, one
// plane through both leaves an RMS of about 0.003, far over `exact`).
TEST(FitShapeMerge, ExactPatchesAStepApartStayTwo) {
  for (const double exact : {0.0, 1e-4}) {
    SCOPED_TRACE(exact > 0.0 ? "exact points" : "noisy points");
    std::vector<Vec3> points;
    std::vector<DetectedShape> shapes;
    shapes.push_back(patch(points, 0.0, 4.0, 0.0));
    shapes.push_back(patch(points, 4.4, 8.4, -0.006));
    std::vector<int> assignment(points.size(), -1);
    for (std::size_t s = 0; s < shapes.size(); ++s) {
      for (auto i : shapes[s].inliers) assignment[i] = static_cast<int>(s);
    }
    const std::size_t merges = detail::merge_same_surface(points, shapes, assignment, 0.01, exact);
    EXPECT_EQ(merges, exact > 0.0 ? 0u : 1u);
    EXPECT_EQ(shapes.size(), exact > 0.0 ? 2u : 1u);
  }
}

}  // namespace
}  // namespace csgtile::fit
