// The union of footprint polygons that tile a region edge to edge (footprint_union.h), the
// LoD1.3 block's one prism per level: cases with known answers, and the cases it must refuse.

#include "footprint_union.h"

#include <gtest/gtest.h>

#include <cmath>

#include "csgtile/kernel/location.h"
#include "csgtile/kernel/polygon2d.h"

namespace csgtile::assembly::detail {
namespace {

using kernel::Vec2;

constexpr double kTolerance = 1e-6;

FootprintPolygon box(double x0, double y0, double x1, double y1) {
  return {{{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}}, {}};
}

double area_of(const std::vector<FootprintPolygon>& polygons) {
  double a = 0.0;
  for (const auto& p : polygons) a += kernel::polygon_area(p.outer, p.holes);
  return a;
}

TEST(FootprintUnion, TwoRoomsSharingAWallAreOneRectangle) {
  const auto u = union_of_tiles({box(0, 0, 4, 3), box(4, 0, 10, 3)}, kTolerance);
  ASSERT_TRUE(u.has_value());
  ASSERT_EQ(u->size(), 1u);
  // The shared wall's ends were the only vertices on the long sides: four corners are left.
  EXPECT_EQ(u->front().outer.size(), 4u);
  EXPECT_TRUE(u->front().holes.empty());
  EXPECT_GT(kernel::ring_area(u->front().outer), 0.0);
  EXPECT_DOUBLE_EQ(area_of(*u), 30.0);
}

TEST(FootprintUnion, ACornerOnANeighboursWallSplitsIt) {
  // An L: the long room's wall along y = 3 runs past the small room's corner at (4, 3); a
  // corner of the second room differs from the first room's in its last bits.
  const FootprintPolygon long_room = box(0, 0, 10, 3);
  FootprintPolygon small_room = box(0, 3, 4, 6);
  small_room.outer[0] = Vec2(0.0, 3.0 + 1e-12);
  const auto u = union_of_tiles({long_room, small_room}, kTolerance);
  ASSERT_TRUE(u.has_value());
  ASSERT_EQ(u->size(), 1u);
  EXPECT_EQ(u->front().outer.size(), 6u);  // an L has six corners
  EXPECT_NEAR(area_of(*u), 42.0, 1e-9);
}

TEST(FootprintUnion, RoomsAroundACourtyardLeaveItAHole) {
  // Four wings around a 2 × 2 courtyard, each ring clockwise as a face seen from below gives it.
  std::vector<FootprintPolygon> wings = {box(0, 0, 6, 2), box(4, 2, 6, 4), box(0, 4, 6, 6),
                                         box(0, 2, 2, 4)};
  for (auto& w : wings) std::reverse(w.outer.begin(), w.outer.end());
  const auto u = union_of_tiles(wings, kTolerance);
  ASSERT_TRUE(u.has_value());
  ASSERT_EQ(u->size(), 1u);
  ASSERT_EQ(u->front().holes.size(), 1u);
  EXPECT_LT(kernel::ring_area(u->front().holes.front()), 0.0);
  EXPECT_NEAR(kernel::ring_area(u->front().holes.front()), -4.0, 1e-12);
  EXPECT_NEAR(area_of(*u), 32.0, 1e-12);
}

TEST(FootprintUnion, AnIslandInACourtyardIsAPieceOfItsOwn) {
  const auto u = union_of_tiles(
      {box(0, 0, 10, 2), box(8, 2, 10, 8), box(0, 8, 10, 10), box(0, 2, 2, 8), box(4, 4, 6, 6)},
      kTolerance);
  ASSERT_TRUE(u.has_value());
  ASSERT_EQ(u->size(), 2u);
  std::size_t holes = 0;
  for (const auto& p : *u) holes += p.holes.size();
  EXPECT_EQ(holes, 1u);
  EXPECT_NEAR(area_of(*u), 64.0 + 4.0, 1e-12);
}

TEST(FootprintUnion, SeparateBuildingsStaySeparate) {
  const auto u = union_of_tiles({box(0, 0, 2, 2), box(5, 0, 7, 2), box(2, 0, 3, 2)}, kTolerance);
  ASSERT_TRUE(u.has_value());
  ASSERT_EQ(u->size(), 2u);
  EXPECT_NEAR(area_of(*u), 10.0, 1e-12);
}

TEST(FootprintUnion, WhatDoesNotTileIsRefused) {
  // Overlapping rooms: their union is smaller than their sum.
  EXPECT_FALSE(union_of_tiles({box(0, 0, 4, 3), box(3, 0, 8, 3)}, kTolerance).has_value());
  // The same room twice.
  EXPECT_FALSE(union_of_tiles({box(0, 0, 4, 3), box(0, 0, 4, 3)}, kTolerance).has_value());
  // Two rooms meeting at a corner only: the union would touch itself there.
  EXPECT_FALSE(union_of_tiles({box(0, 0, 2, 2), box(2, 2, 4, 4)}, kTolerance).has_value());
  // A room inside another (a tower standing in a roof that was not cut around it).
  EXPECT_FALSE(union_of_tiles({box(0, 0, 10, 10), box(4, 4, 6, 6)}, kTolerance).has_value());
  // A degenerate ring.
  EXPECT_FALSE(union_of_tiles({{{{0, 0}, {1, 1}}, {}}}, kTolerance).has_value());
}

}  // namespace
}  // namespace csgtile::assembly::detail
