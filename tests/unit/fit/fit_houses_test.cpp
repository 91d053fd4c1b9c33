// Houses of a block (issue #18 item 2, houses.cpp): parts whose roofs meet are one house, a
// height step separates two; what is too small, too thin or enclosed joins its neighbour.

#include <gtest/gtest.h>

#include <vector>

#include "house_overlaps.h"
#include "houses.h"

namespace csgtile::fit::detail {
namespace {

// A w × d rectangle's part: its area and perimeter, `outside` of it on the outside.
HousePart rect(double w, double d, double outside) { return {w * d, 2.0 * (w + d), outside}; }

PartBoundary meet(int a, int b, double length, long long edges, long long continuous) {
  PartBoundary e;
  e.a = a;
  e.b = b;
  e.length = length;
  e.edges = edges;
  e.continuous = continuous;
  return e;
}

TEST(FitHouses, RoofsMeetingAreOneHouseStepsSeparateHouses) {
  // Three 7 × 10 m houses in a row, each two slopes of 7 × 5 m meeting at its ridge; the
  // gables between houses are steps (three tenths of their edges at one height).
  std::vector<HousePart> parts;
  for (int h = 0; h < 3; ++h) {
    const double ends = h == 1 ? 0.0 : 5.0;  // the end houses' gable walls are facades
    parts.push_back(rect(7, 5, 7 + ends));
    parts.push_back(rect(7, 5, 7 + ends));
  }
  std::vector<PartBoundary> b;
  for (int h = 0; h < 3; ++h) b.push_back(meet(2 * h, 2 * h + 1, 7, 14, 14));  // ridges
  for (int h = 0; h < 2; ++h) {
    b.push_back(meet(2 * h, 2 * h + 2, 5, 10, 3));  // gables
    b.push_back(meet(2 * h + 1, 2 * h + 3, 5, 10, 3));
  }
  EXPECT_EQ(group_houses(parts, b, HouseRules{}), (std::vector<int>{0, 0, 1, 1, 2, 2}));
  // Gables at one height: one roof over the row, one house.
  for (auto& e : b) e.continuous = e.edges;
  EXPECT_EQ(group_houses(parts, b, HouseRules{}), (std::vector<int>{0, 0, 0, 0, 0, 0}));
}

TEST(FitHouses, SmallThinAndEnclosedPartsJoinTheHouseTheyShareMostWith) {
  // A 20 × 12 m flat roof (part 0), a 4 × 3 m dormer at its edge (1), a parapet ring 0.4 m
  // wide around a second roof of 20 × 12 m (2, the ring 3), and a 6 × 6 m plant room inside
  // that roof (4): steps all around each.
  std::vector<HousePart> parts{rect(20, 12, 50),
                               rect(4, 3, 4),
                               rect(20, 12, 0),
                               {0.4 * 64.0, 2.0 * 64.0, 64.0},
                               rect(6, 6, 0)};
  std::vector<PartBoundary> b{meet(0, 1, 10, 20, 0), meet(0, 3, 12, 24, 0), meet(2, 3, 64, 128, 0),
                              meet(2, 4, 24, 48, 0)};
  // The dormer (12 m²) joins its roof; the ring (25.6 m², 0.4 m wide) the roof it shares
  // 64 m with, not the one beside it (12 m); the plant room (no outside wall) its roof.
  EXPECT_EQ(group_houses(parts, b, HouseRules{}), (std::vector<int>{0, 0, 1, 1, 1}));
  // A part with no neighbour stays a house, whatever its size.
  EXPECT_EQ(group_houses({rect(2, 2, 8)}, {}, HouseRules{}), (std::vector<int>{0}));
}

TEST(FitHouses, HousesAreNumberedByTheirFirstPart) {
  std::vector<HousePart> parts{rect(8, 8, 16), rect(8, 8, 16), rect(8, 8, 16)};
  // Parts 0 and 2 are one house (their roofs meet), part 1 another.
  const std::vector<PartBoundary> b{meet(0, 1, 8, 16, 0), meet(1, 2, 8, 16, 0),
                                    meet(0, 2, 8, 16, 16)};
  EXPECT_EQ(group_houses(parts, b, HouseRules{}), (std::vector<int>{0, 1, 0}));
}

TEST(FitHouses, RoofsMeetingAtACornerOnlyAreTwoHouses) {
  // Two 8 × 8 m roofs whose continuous boundary is one metre long (a corner): shorter than a
  // house is wide, no joint.
  std::vector<HousePart> parts{rect(8, 8, 24), rect(8, 8, 24)};
  EXPECT_EQ(group_houses(parts, {meet(0, 1, 1.0, 2, 2)}, HouseRules{}), (std::vector<int>{0, 1}));
  EXPECT_EQ(group_houses(parts, {meet(0, 1, 2.0, 4, 4)}, HouseRules{}), (std::vector<int>{0, 0}));
}

TEST(FitHouses, ASmallHouseJoinsTheNeighbourItSharesMostWithTiesToTheFirst) {
  // A 4 × 4 m shed between two houses: 4 m with house 0, 4 m with house 2 (a tie: the first).
  std::vector<HousePart> parts{rect(8, 8, 24), rect(4, 4, 8), rect(8, 8, 24)};
  std::vector<PartBoundary> b{meet(0, 1, 4, 8, 0), meet(1, 2, 4, 8, 0)};
  EXPECT_EQ(group_houses(parts, b, HouseRules{}), (std::vector<int>{0, 0, 1}));
  b[1].length = 5;  // now longer with house 2
  EXPECT_EQ(group_houses(parts, b, HouseRules{}), (std::vector<int>{0, 1, 1}));
}

// A box of `size` with its minimum corner at `corner`, of `house` (derived).
geo::ScenePrimitive box(const kernel::Vec3& corner, const kernel::Vec3& size,
                        const std::string& house) {
  geo::ScenePrimitive p;
  p.spec.type = kernel::PrimitiveType::Box;
  p.spec.size = size;
  p.spec.placement = kernel::Location::translation(corner);
  p.house = house;
  return p;
}

TEST(FitHouses, HousesWhoseSolidsOverlapAreOne) {
  // Region 0: houses h0 and h1 touching along x = 8 (a party wall). Region 1: house h0, a
  // storey that overlaps region 0's h1 by 1 m; region 2 (no houses) overlaps region 1's; a
  // footprint building overlapping h0 takes no part.
  std::vector<geo::ScenePrimitive> prims{
      box({0, 0, 0}, {8, 10, 6}, "r0-h0"),  box({8, 0, 0}, {8, 10, 9}, "r0-h1"),
      box({15, 0, 3}, {6, 10, 6}, "r1-h0"), box({20, 2, 0}, {3, 3, 4}, ""),
      box({2, 2, 0}, {3, 3, 7}, ""),
  };
  prims.back().building = "F";
  const std::vector<int> region{0, 0, 1, 2, 3};
  join_overlapping_houses(prims, region, 0.05);
  EXPECT_EQ(prims[0].house, "r0-h0");  // touches h1 only
  EXPECT_EQ(prims[1].house, "r0-h1");
  EXPECT_EQ(prims[2].house, "r0-h1");  // overlaps it
  EXPECT_EQ(prims[3].house, "r0-h1");  // the region without houses overlapping it
  EXPECT_EQ(prims[4].house, "");       // a footprint's
  // Touching only (a face in common): nothing joins.
  std::vector<geo::ScenePrimitive> row{box({0, 0, 0}, {8, 10, 6}, "r0-h0"),
                                       box({8, 0, 0}, {8, 10, 9}, "r1-h0")};
  join_overlapping_houses(row, {0, 1}, 0.05);
  EXPECT_EQ(row[1].house, "r1-h0");
}

}  // namespace
}  // namespace csgtile::fit::detail
