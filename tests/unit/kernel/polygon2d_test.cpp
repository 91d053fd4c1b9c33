// Rings and polygons in the plane (kernel/polygon2d.h) and the one ray–box test
// (kernel/bounding_box.h): the helpers the builders, the classifier, the fitting and the scan
// simulator share.

#include "csgtile/kernel/polygon2d.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "csgtile/kernel/bounding_box.h"

namespace csgtile::kernel {
namespace {

const std::vector<Vec2> kSquare{{0, 0}, {4, 0}, {4, 4}, {0, 4}};
const std::vector<Vec2> kHole{{1, 1}, {1, 2}, {2, 2}, {2, 1}};  // clockwise

TEST(Polygon2d, AreasInsideAndDistances) {
  EXPECT_EQ(ring_area(kSquare), 16.0);
  EXPECT_EQ(ring_area(kHole), -1.0);
  EXPECT_EQ(polygon_area(kSquare, {kHole}), 15.0);
  EXPECT_EQ(polygon_perimeter(kSquare, {kHole}), 20.0);
  EXPECT_TRUE(inside_ring(Vec2(1.5, 1.5), kSquare));
  EXPECT_FALSE(inside_polygon(Vec2(1.5, 1.5), kSquare, {kHole}));
  EXPECT_TRUE(inside_polygon(Vec2(3, 3), kSquare, {kHole}));
  EXPECT_FALSE(inside_ring(Vec2(5, 1), kSquare));
  EXPECT_DOUBLE_EQ(boundary_distance(Vec2(1.5, 2.5), kSquare, {kHole}), 0.5);
  EXPECT_DOUBLE_EQ(segment_distance(Vec2(2, 3), Vec2(0, 0), Vec2(4, 0)), 3.0);
}

TEST(Polygon2d, CleaningAndValidity) {
  // A repeated vertex, a straight middle point and the closing vertex repeated.
  const std::vector<Vec2> messy{{0, 0}, {2, 0}, {2, 0}, {4, 0}, {4, 4}, {0, 4}, {0, 0}};
  EXPECT_EQ(clean_ring(messy, 1e-9), kSquare);
  EXPECT_FALSE(ring_self_intersects(kSquare));
  const std::vector<Vec2> bow{{0, 0}, {4, 4}, {4, 0}, {0, 4}};
  EXPECT_TRUE(ring_self_intersects(bow));
  EXPECT_FALSE(rings_intersect(kSquare, kHole));
  EXPECT_TRUE(rings_intersect(kSquare, {{3, 3}, {5, 3}, {5, 5}}));
}

TEST(BoxRay, ClipsToTheBoxAndTreatsFlatAxesAsSlabs) {
  BoundingBox box;
  box.add(Vec3(1, 1, 1));
  box.add(Vec3(2, 3, 4));
  double t0 = 0, t1 = std::numeric_limits<double>::infinity();
  ASSERT_TRUE(BoxRay(Vec3(0, 2, 2), Vec3(1, 0, 0)).clip(box, t0, t1));
  EXPECT_EQ(t0, 1.0);
  EXPECT_EQ(t1, 2.0);
  // Flat in y and z, outside the y slab: a miss whatever t.
  t0 = 0, t1 = 100;
  EXPECT_FALSE(BoxRay(Vec3(0, 5, 2), Vec3(1, 0, 0)).clip(box, t0, t1));
  // Pointing away, and stopping short.
  t0 = 0, t1 = 100;
  EXPECT_FALSE(BoxRay(Vec3(0, 2, 2), Vec3(-1, 0, 0)).clip(box, t0, t1));
  t0 = 0, t1 = 0.5;
  EXPECT_FALSE(BoxRay(Vec3(0, 2, 2), Vec3(1, 0, 0)).clip(box, t0, t1));
  // Touching a corner counts; an empty box is never met.
  t0 = 0, t1 = 100;
  EXPECT_TRUE(BoxRay(Vec3(0, 0, 0), Vec3(1, 1, 1)).clip(box, t0, t1));
  EXPECT_EQ(t0, 1.0);
  t0 = 0, t1 = 100;
  EXPECT_FALSE(BoxRay(Vec3(0, 0, 0), Vec3(1, 1, 1)).clip(BoundingBox{}, t0, t1));
}

}  // namespace
}  // namespace csgtile::kernel
