// The one grid of a city run (kernel/grid.h): which cell holds a point, the cells' order and
// the halo tests on boxes.

#include "csgtile/kernel/grid.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

namespace csgtile::kernel {
namespace {

BoundingBox box_xy(double x0, double y0, double x1, double y1) {
  BoundingBox b;
  b.add(Vec3(x0, y0, 0));
  b.add(Vec3(x1, y1, 1));
  return b;
}

TEST(Grid, CellsAreOrderedByColumnThenRow) {
  std::vector<GridCell> cells{{2, 0}, {1, 5}, {1, -3}, {-4, 9}};
  std::sort(cells.begin(), cells.end());
  EXPECT_EQ(cells, (std::vector<GridCell>{{-4, 9}, {1, -3}, {1, 5}, {2, 0}}));
  EXPECT_EQ((GridCell{12, -3}).name(), "c12_r-3");
  auto back = GridCell::parse("c-7_r123456789");
  ASSERT_TRUE(back.ok());
  EXPECT_EQ(back.value(), (GridCell{-7, 123456789}));
  EXPECT_FALSE(GridCell::parse("c1r2").ok());
}

TEST(Grid, ACellsCoreHoldsExactlyThePointsItsEdgesBound) {
  // A cell size with no exact binary form: the division and the edges round differently, and
  // cell_of must follow the edges (a neighbour's upper edge is this cell's lower edge).
  const Grid grid{0.3, -0.7, 0.1, 0.0};
  for (std::int64_t c = -50; c <= 50; ++c) {
    const double x = grid.edge_x(c);
    EXPECT_EQ(grid.cell_of(x, 0).column, c) << c;
    EXPECT_EQ(grid.cell_of(std::nextafter(x, -1e9), 0).column, c - 1) << c;
  }
  for (std::int64_t r = -50; r <= 50; ++r) {
    EXPECT_EQ(grid.cell_of(0, grid.edge_y(r)).row, r) << r;
  }
}

TEST(Grid, HaloTestsOnBoxes) {
  const Grid grid{0, 0, 100, 10};
  const GridCell cell{1, 1};  // core [100, 200) × [100, 200), halo [90, 210]
  EXPECT_TRUE(grid.meets_halo(box_xy(80, 80, 90, 90), cell));  // touching the halo's corner
  EXPECT_FALSE(grid.meets_halo(box_xy(80, 80, 89.9, 150), cell));
  EXPECT_FALSE(grid.meets_halo(BoundingBox{}, cell));
  EXPECT_TRUE(grid.within_halo(box_xy(90, 90, 210, 210), cell));
  EXPECT_FALSE(grid.within_halo(box_xy(90, 90, 210.1, 150), cell));
  EXPECT_TRUE(grid.within_halo(BoundingBox{}, cell));
}

}  // namespace
}  // namespace csgtile::kernel
