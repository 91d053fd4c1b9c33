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

TEST(GridRings, AreaOrientationAndMidpointsAreExact) {
  // An L of unit cells at coordinates near 1e8: doubles would round the products.
  const long long o = 100'000'000;
  const std::vector<GridVertex> l{{o, o},         {o + 3, o},     {o + 3, o + 1},
                                  {o + 1, o + 1}, {o + 1, o + 3}, {o, o + 3}};
  EXPECT_EQ(grid_ring_area2(l), 10);  // 5 cells, doubled
  const std::vector<GridVertex> reversed(l.rbegin(), l.rend());
  EXPECT_EQ(grid_ring_area2(reversed), -10);
  EXPECT_EQ(grid_orientation(l[0], l[1], l[2]), 1);
  EXPECT_EQ(grid_orientation(l[0], l[2], l[1]), -1);
  EXPECT_EQ(grid_orientation(l[0], l[1], {o + 7, o}), 0);
  // Midpoints of segments inside the L, in its notch, and on its boundary's far side.
  EXPECT_TRUE(grid_midpoint_inside({o, o}, {o + 1, o + 1}, l));
  EXPECT_FALSE(grid_midpoint_inside({o + 2, o + 2}, {o + 3, o + 3}, l));
  EXPECT_TRUE(grid_midpoint_inside({o + 2, o}, {o + 3, o + 1}, reversed));
}

TEST(GridRings, SegmentsConflictUnlessTheyOnlyShareAnEnd) {
  const GridVertex a{0, 0}, b{4, 0}, c{2, -2}, d{2, 2}, e{4, 4}, f{8, 0};
  EXPECT_TRUE(grid_segments_conflict(a, b, c, d));       // crossing
  EXPECT_FALSE(grid_segments_conflict(a, b, b, e));      // a shared end, turning
  EXPECT_FALSE(grid_segments_conflict(a, b, b, f));      // a shared end, going straight on
  EXPECT_TRUE(grid_segments_conflict(a, b, b, {2, 0}));  // folding back along a-b
  EXPECT_TRUE(grid_segments_conflict(a, b, b, a));       // the same segment twice
  EXPECT_TRUE(grid_segments_conflict(a, b, {2, 0}, e));  // touching inside a-b
  EXPECT_FALSE(grid_segments_conflict(a, b, {5, 1}, e));
}

}  // namespace
}  // namespace csgtile::kernel
