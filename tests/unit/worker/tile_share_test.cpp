// Which buildings across a tile's edges its fit makes (city/tile_share.h): four 100 m tiles in
// a 2 × 2 grid, halo 20 m. Every tile computes the same owner for a building: the first tile
// in run order holding the centre of its box, when the building lies within that tile's
// extent grown by the halo; larger buildings are fitted in parts.

#include "city/tile_share.h"

#include <gtest/gtest.h>

namespace csgtile::worker::city {
namespace {

using fit::ShareKind;
using kernel::Vec2;

// Tiles 0..3: (0,0), (100,0), (0,100), (100,100), each 100 m square (shared edges).
std::vector<TileExtent> grid() {
  std::vector<TileExtent> out;
  for (std::size_t k = 0; k < 4; ++k) {
    const double x = 100.0 * static_cast<double>(k % 2), y = 100.0 * static_cast<double>(k / 2);
    out.push_back({k, "t" + std::to_string(k), {x, y, x + 100.0, y + 100.0}});
  }
  return out;
}

TileNeighbourhood around(std::size_t k) {
  const auto all = grid();
  TileNeighbourhood n;
  n.self = all[k];
  n.halo = 20.0;
  const auto near = neighbours_of(all, 40.0);
  for (std::size_t j : near[k]) n.neighbours.push_back(all[j]);
  return n;
}

TEST(TileShare, NeighboursAreTheTilesWithinTheDistance) {
  std::vector<TileExtent> tiles = grid();
  tiles.push_back({4, "far", {500, 500, 600, 600}});
  const auto near = neighbours_of(tiles, 40.0);
  EXPECT_EQ(near[0], (std::vector<std::size_t>{1, 2, 3}));
  EXPECT_EQ(near[3], (std::vector<std::size_t>{0, 1, 2}));
  EXPECT_TRUE(near[4].empty());
  const auto apart = neighbours_of({{0, "a", {0, 0, 10, 10}}, {1, "b", {50.5, 0, 60, 10}}}, 40.0);
  EXPECT_TRUE(apart[0].empty());
  EXPECT_EQ(apart[1], std::vector<std::size_t>{});
  EXPECT_EQ(neighbours_of({{0, "a", {0, 0, 10, 10}}, {1, "b", {49, 0, 60, 10}}}, 40.0)[0],
            std::vector<std::size_t>{1});
}

TEST(TileShare, AFootprintAcrossAnEdgeIsItsCentresTile) {
  // A house from x 90 to 104: centre 97, in tile 0; within tile 0's halo.
  const Vec2 lo(90, 40), hi(104, 52);
  EXPECT_EQ(footprint_share(around(0), lo, hi), ShareKind::whole);
  EXPECT_EQ(footprint_share(around(1), lo, hi), ShareKind::none);
  EXPECT_EQ(footprint_share(around(2), lo, hi), ShareKind::none);
  // Its centre on the shared edge x = 100: the first tile in run order holding it.
  EXPECT_EQ(footprint_share(around(0), Vec2(95, 40), Vec2(105, 52)), ShareKind::whole);
  EXPECT_EQ(footprint_share(around(1), Vec2(95, 40), Vec2(105, 52)), ShareKind::none);
  // At the corner of four tiles: tile 3 holds the centre (101, 101) alone.
  for (std::size_t k = 0; k < 4; ++k) {
    EXPECT_EQ(footprint_share(around(k), Vec2(92, 92), Vec2(110, 110)),
              k == 3 ? ShareKind::whole : ShareKind::none)
        << k;
  }
}

TEST(TileShare, AFootprintLargerThanTheHaloIsFittedInParts) {
  // 60 m long across x = 100: past tile 0's halo (120) and tile 1's (80).
  const Vec2 lo(70, 40), hi(130, 50);
  EXPECT_EQ(footprint_share(around(0), lo, hi), ShareKind::own_points);
  EXPECT_EQ(footprint_share(around(1), lo, hi), ShareKind::own_points);
  // A tile it does not reach makes none of it.
  EXPECT_EQ(footprint_share(around(2), lo, hi), ShareKind::none);
}

TEST(TileShare, ClustersSeenWholeGoToTheirOwner) {
  // Seen whole by tiles 0 and 1 (within both read regions, 0.5 m clustering distance).
  EXPECT_EQ(cluster_share(around(0), Vec2(96, 10), Vec2(110, 20), 0.5), ShareKind::none);
  EXPECT_EQ(cluster_share(around(1), Vec2(96, 10), Vec2(110, 20), 0.5), ShareKind::whole);
  // One reaching within the clustering distance of where tile 1 stops reading (x = 80) may
  // go on past it: tile 1 keeps its own points; tile 0 sees it whole, and since its owner
  // (tile 1, holding the centre 100.1) cannot, keeps its own points too.
  EXPECT_EQ(cluster_share(around(1), Vec2(80.2, 10), Vec2(120, 20), 0.5), ShareKind::own_points);
  EXPECT_EQ(cluster_share(around(0), Vec2(80.2, 10), Vec2(120, 20), 0.5), ShareKind::own_points);
  // Seen whole by tiles 0 and 1 but reaching tile 3, which sees only part of it (its read
  // region starts at y = 80): tile 3 keeps its own points, the owner (tile 1) fits it whole.
  EXPECT_EQ(cluster_share(around(3), Vec2(95, 75), Vec2(108, 105), 0.5), ShareKind::own_points);
  EXPECT_EQ(cluster_share(around(1), Vec2(95, 75), Vec2(108, 105), 0.5), ShareKind::whole);
  EXPECT_EQ(cluster_share(around(0), Vec2(95, 75), Vec2(108, 105), 0.5), ShareKind::none);
  // Entirely a neighbour's, within this tile's halo: the neighbour's.
  EXPECT_EQ(cluster_share(around(0), Vec2(105, 10), Vec2(115, 20), 0.5), ShareKind::none);
}

}  // namespace
}  // namespace csgtile::worker::city
