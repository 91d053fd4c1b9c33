// City grid and tile index: one core per point, overlapping halos, deterministic indexes.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "csgtile/geo/crs.h"
#include "csgtile/geo/georeference.h"
#include "csgtile/geo/tiling.h"

namespace csgtile::geo {
namespace {

using kernel::Vec3;

CityGrid grid(double origin_x, double origin_y, double size, double halo, int epsg = 28992) {
  auto g = CityGrid::create(crs_from_epsg(epsg).value(), GridSpec{origin_x, origin_y, size, halo});
  EXPECT_TRUE(g.ok());
  return g.value();
}

TEST(TilingGrid, EveryPointIsInExactlyOneCore) {
  // Awkward sizes (0.1-style binary fractions, negative origins) and points on cell edges.
  for (const GridSpec spec : {GridSpec{0, 0, 0.1, 0.01}, GridSpec{-1234.5, 98765.25, 250, 20},
                              GridSpec{155000, 463000, 1000, 50}, GridSpec{1e-3, -7, 3.3, 0}}) {
    const CityGrid g = grid(spec.origin_x, spec.origin_y, spec.cell_size, spec.halo);
    std::mt19937_64 rng(17);
    std::uniform_real_distribution<double> offset(-40, 40);
    std::uniform_int_distribution<int> edge(-40, 40);
    for (int i = 0; i < 20000; ++i) {
      double x = spec.origin_x + offset(rng) * spec.cell_size;
      double y = spec.origin_y + offset(rng) * spec.cell_size;
      if (i % 3 == 0)
        x = spec.origin_x + edge(rng) * spec.cell_size;  // exactly on (computed) edges
      if (i % 5 == 0) y = spec.origin_y + edge(rng) * spec.cell_size;
      const GridCell c = g.cell_of(x, y);
      ASSERT_TRUE(g.in_core(c, x, y)) << c.name() << " x=" << x << " y=" << y;
      int cores = 0;
      for (int dr = -1; dr <= 1; ++dr) {
        for (int dc = -1; dc <= 1; ++dc)
          cores += g.in_core(GridCell{c.column + dc, c.row + dr}, x, y) ? 1 : 0;
      }
      ASSERT_EQ(cores, 1) << "x=" << x << " y=" << y;
      ASSERT_TRUE(g.in_halo(c, x, y));
    }
  }
}

TEST(TilingGrid, HalosOverlapNeighbours) {
  const CityGrid g = grid(0, 0, 100, 10);
  const GridCell a{3, 4};
  const GridCell east{4, 4};
  const Bounds2 ha = g.halo_bounds(a);
  const Bounds2 he = g.halo_bounds(east);
  EXPECT_DOUBLE_EQ(ha.max_x - he.min_x, 20.0);  // 2·halo
  EXPECT_TRUE(ha.intersects(he));
  // A point 5 units either side of the shared edge lies in both halos, one core.
  for (double x : {395.0, 405.0}) {
    EXPECT_TRUE(g.in_halo(a, x, 450));
    EXPECT_TRUE(g.in_halo(east, x, 450));
    EXPECT_NE(g.in_core(a, x, 450), g.in_core(east, x, 450));
  }
  EXPECT_FALSE(g.in_halo(a, 411, 450));
  EXPECT_DOUBLE_EQ(g.core_bounds(a).min_x, 300.0);
  EXPECT_DOUBLE_EQ(g.core_bounds(a).max_y, 500.0);
}

TEST(TilingGrid, HostileCoordinatesNeitherHangNorOverflow) {
  const CityGrid g = grid(0, 0, 0.5, 0.1);
  for (double v : std::initializer_list<double>{NAN, INFINITY, -INFINITY, 1e300, -1e300, 1e17}) {
    const GridCell c = g.cell_of(v, v);
    EXPECT_FALSE(g.in_core(c, v, v)) << v;
  }
  auto far = g.cells_meeting(Bounds2{1e300, 1e300, 1e300, 1e300}, true);
  EXPECT_TRUE(far.ok());
}

TEST(TilingGrid, InvalidSpecsAreRefused) {
  const Crs crs = crs_from_epsg(28992).value();
  EXPECT_FALSE(CityGrid::create(crs, GridSpec{0, 0, 0, 0}).ok());
  EXPECT_FALSE(CityGrid::create(crs, GridSpec{0, 0, 100, -1}).ok());
  EXPECT_FALSE(CityGrid::create(crs, GridSpec{0, 0, 100, 100}).ok());
  EXPECT_FALSE(CityGrid::create(crs, GridSpec{NAN, 0, 100, 1}).ok());
  Crs broken = crs;
  broken.linear_unit.metres = -1;
  EXPECT_FALSE(CityGrid::create(broken, GridSpec{0, 0, 100, 1}).ok());
}

TEST(TilingGrid, CellsMeetingBoundsAreOrderedAndExact) {
  const CityGrid g = grid(0, 0, 100, 10);
  auto cores = g.cells_meeting(Bounds2{150, 150, 250, 250}, false);
  ASSERT_TRUE(cores.ok());
  EXPECT_EQ(cores.value(), (std::vector<GridCell>{{1, 1}, {1, 2}, {2, 1}, {2, 2}}));
  // Touching a core's upper edge does not meet that core (half-open) ...
  auto touching = g.cells_meeting(Bounds2{150, 150, 200, 199}, false);
  EXPECT_EQ(touching.value(), (std::vector<GridCell>{{1, 1}, {2, 1}}));
  // ... but halos are closed: 10 units of halo reach into the neighbours.
  auto halos = g.cells_meeting(Bounds2{150, 150, 185, 185}, true);
  EXPECT_EQ(halos.value(), (std::vector<GridCell>{{1, 1}}));
  auto halos2 = g.cells_meeting(Bounds2{150, 150, 191, 191}, true);
  EXPECT_EQ(halos2.value(), (std::vector<GridCell>{{1, 1}, {1, 2}, {2, 1}, {2, 2}}));
  EXPECT_FALSE(g.cells_meeting(Bounds2{0, 0, 1e9, 1e9}, true).ok());
  EXPECT_FALSE(g.cells_meeting(Bounds2{5, 0, 1, 1}, true).ok());
}

TEST(TilingGridCell, TextRoundTrip) {
  for (const GridCell c : {GridCell{0, 0}, GridCell{12, -3}, GridCell{-7, 123456789}}) {
    auto back = GridCell::parse(c.name());
    ASSERT_TRUE(back.ok()) << c.name();
    EXPECT_EQ(back.value(), c);
  }
  EXPECT_EQ(GridCell({12, -3}).name(), "c12_r-3");
  for (const char* bad : {"", "c1", "c1_r", "x1_r2", "c1_r2x", "c_r2", "c1_x2"})
    EXPECT_FALSE(GridCell::parse(bad).ok()) << bad;
}

std::vector<InputBounds> random_inputs(std::uint64_t seed, int n) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> x(80000, 90000), y(440000, 450000), size(100, 1500);
  std::vector<InputBounds> inputs;
  for (int i = 0; i < n; ++i) {
    const double x0 = x(rng), y0 = y(rng);
    inputs.push_back(
        InputBounds{"s3://ahn/tile_" + std::to_string(i % 37) + "_" + std::to_string(i) + ".las",
                    Bounds2{x0, y0, x0 + size(rng), y0 + size(rng)}});
  }
  return inputs;
}

TEST(TilingIndex, DeterministicWhateverTheInputOrder) {
  const CityGrid g = grid(80000, 440000, 1000, 50);
  const auto inputs = random_inputs(99, 200);
  auto first = TileIndex::build(g, inputs);
  ASSERT_TRUE(first.ok());
  std::mt19937_64 rng(5);
  for (int trial = 0; trial < 5; ++trial) {
    auto shuffled = inputs;
    std::shuffle(shuffled.begin(), shuffled.end(), rng);
    auto again = TileIndex::build(g, shuffled);
    ASSERT_TRUE(again.ok());
    ASSERT_EQ(again.value().cells().size(), first.value().cells().size());
    for (std::size_t i = 0; i < first.value().cells().size(); ++i) {
      EXPECT_EQ(again.value().cells()[i].cell, first.value().cells()[i].cell);
      EXPECT_EQ(again.value().cells()[i].inputs, first.value().cells()[i].inputs);
    }
    for (std::size_t i = 0; i < inputs.size(); ++i) {
      EXPECT_EQ(again.value().inputs()[i].name, first.value().inputs()[i].name);
    }
  }
  // Cells in (column, row) order; inputs ascending; names sorted.
  const auto& cells = first.value().cells();
  EXPECT_TRUE(
      std::is_sorted(cells.begin(), cells.end(),
                     [](const CellInputs& a, const CellInputs& b) { return a.cell < b.cell; }));
  for (const CellInputs& c : cells) EXPECT_TRUE(std::is_sorted(c.inputs.begin(), c.inputs.end()));
  const auto& in = first.value().inputs();
  EXPECT_TRUE(std::is_sorted(in.begin(), in.end(), [](const InputBounds& a, const InputBounds& b) {
    return a.name < b.name;
  }));
}

TEST(TilingIndex, EachInputFeedsExactlyTheCellsWhoseHaloItMeets) {
  const CityGrid g = grid(80000, 440000, 1000, 50);
  auto index = TileIndex::build(g, random_inputs(3, 60));
  ASSERT_TRUE(index.ok());
  const auto& inputs = index.value().inputs();
  for (std::int64_t row = -2; row < 13; ++row) {
    for (std::int64_t column = -2; column < 13; ++column) {
      const GridCell cell{column, row};
      std::vector<std::size_t> expected;
      for (std::size_t i = 0; i < inputs.size(); ++i) {
        if (g.halo_bounds(cell).intersects(inputs[i].bounds)) expected.push_back(i);
      }
      const auto got = index.value().inputs_for(cell);
      EXPECT_EQ(std::vector<std::size_t>(got.begin(), got.end()), expected) << cell.name();
    }
  }
}

TEST(TilingIndex, PointsOfSeveralFilesGatheredWithTheHalo) {
  const CityGrid g = grid(0, 0, 100, 10);
  auto index = TileIndex::build(g, {InputBounds{"b.las", Bounds2{95, 0, 195, 100}},
                                    InputBounds{"a.las", Bounds2{0, 0, 100, 100}}});
  ASSERT_TRUE(index.ok());
  const auto feeding = index.value().inputs_for(GridCell{0, 0});
  ASSERT_EQ(feeding.size(), 2u);
  EXPECT_EQ(index.value().inputs()[feeding[0]].name, "a.las");
  const std::vector<Vec3> file_a = {{5, 5, 0}, {99, 50, 0}, {50, 99.5, 0}};
  const std::vector<Vec3> file_b = {{100, 50, 1}, {109, 50, 2}, {111, 50, 3}};
  EXPECT_EQ(select_points(g, GridCell{0, 0}, file_a, false), (std::vector<std::size_t>{0, 1, 2}));
  EXPECT_EQ(select_points(g, GridCell{0, 0}, file_b, false), (std::vector<std::size_t>{}));
  EXPECT_EQ(select_points(g, GridCell{0, 0}, file_b, true), (std::vector<std::size_t>{0, 1}));
  EXPECT_FALSE(TileIndex::build(g, {InputBounds{"bad.las", Bounds2{1, 1, 0, 0}}}).ok());
}

TEST(TilingBounds, TransformBoundsBetweenCrss) {
  const Crs rd = crs_from_epsg(28992).value();
  const Crs utm = crs_from_epsg(25831).value();
  const Bounds2 delft{84000, 445000, 86000, 448000};
  auto b = transform_bounds(rd, utm, delft);
  ASSERT_TRUE(b.ok()) << b.error().message;
  // The grids are rotated ~1.9 degrees against each other at Delft (both convergences), so
  // the box around the rotated rectangle is ~100 m wider and ~65 m taller.
  EXPECT_GT(b.value().max_x - b.value().min_x, 2000);
  EXPECT_LT(b.value().max_x - b.value().min_x, 2150);
  EXPECT_GT(b.value().max_y - b.value().min_y, 3000);
  EXPECT_LT(b.value().max_y - b.value().min_y, 3100);
  for (const Vec3& corner : {Vec3(84000, 445000, 0), Vec3(86000, 448000, 0), Vec3(84000, 448000, 0),
                             Vec3(86000, 445000, 0)}) {
    auto p = transform_point(rd, utm, corner);
    ASSERT_TRUE(p.ok());
    EXPECT_TRUE(p.value().x() >= b.value().min_x && p.value().x() <= b.value().max_x);
    EXPECT_TRUE(p.value().y() >= b.value().min_y && p.value().y() <= b.value().max_y);
  }
  // Every corner of the input lies inside the output.
  auto back = transform_bounds(utm, rd, b.value());
  ASSERT_TRUE(back.ok());
  EXPECT_LE(back.value().min_x, delft.min_x + 1e-6);
  EXPECT_GE(back.value().max_y, delft.max_y - 1e-6);
  EXPECT_FALSE(transform_bounds(rd, utm, delft, 1).ok());
}

}  // namespace
}  // namespace csgtile::geo
