// LoD1.2 and LoD1.3 block models and building heights (block_model.h) on buildings with known
// answers.

#include "csgtile/assembly/block_model.h"

#include <gtest/gtest.h>

#include <cmath>

#include "csgtile/kernel/check.h"
#include "csgtile/kernel/explorer.h"
#include "csgtile/kernel/mass_properties.h"
#include "model_builders.h"

namespace csgtile::assembly {
namespace {

using kernel::PrimitiveSpec;
using kernel::Vec2;
using kernel::Vec3;

using test::extrusion_at;
using test::rectangle;

kernel::CsgModel leaf(const PrimitiveSpec& spec) { return test::leaf(spec, "part"); }

// A gable house, 10 × 6 m: eaves at 5 m, ridge at 8 m along x over y = 3. Each roof side's
// height is spread evenly over its area, so the percentiles are 5 + 3q.
TEST(BlockModel, GableHouseHeightsAreTheRoofsExactPercentiles) {
  const kernel::CsgModel house = leaf(test::gable_house());
  auto block = block_model(house);
  ASSERT_TRUE(block.ok()) << block.error().message;
  const BuildingHeights& h = block->heights;
  EXPECT_NEAR(h.ground, 0.0, 1e-9);
  EXPECT_NEAR(h.roof_min, 5.0, 1e-9);
  EXPECT_NEAR(h.roof_max, 8.0, 1e-9);
  EXPECT_NEAR(h.roof_50p, 6.5, 1e-9);
  EXPECT_NEAR(h.roof_70p, 7.1, 1e-9);
  EXPECT_NEAR(h.roof_area, 60.0, 1e-9);
  EXPECT_EQ(h.roof_faces, 2u);
  // The block: the footprint up to 7.1 m, one valid solid, its own history (one extrusion).
  EXPECT_TRUE(kernel::check_shape(block->model.shape).valid());
  EXPECT_NEAR(kernel::mass_properties(block->model.shape).volume, 60.0 * 7.1, 1e-6);
  ASSERT_EQ(block->model.nodes.size(), 1u);
  EXPECT_EQ(block->model.nodes[0].primitive.type, kernel::PrimitiveType::Extrusion);
}

// An L of two parts standing on two levels (a terrain step of 1 m): a flat part up to 5 m
// and a higher one up to 9 m, fused. The footprint is both bottoms, the block stands on the
// lower ground; half of the roof's area lies at 5 m, so the 70th percentile is 9 m.
TEST(BlockModel, PartsOnTwoGroundLevelsMakeOneBlockOverTheWholeFootprint) {
  const kernel::CsgModel low = leaf(extrusion_at(rectangle(0, 0, 10, 6), 0.0, 5.0));
  const kernel::CsgModel high = leaf(extrusion_at(rectangle(10, 0, 16, 10), 1.0, 8.0));
  auto building = kernel::csg_combine({low, high}, kernel::BooleanOp::Fuse);
  ASSERT_TRUE(building.ok()) << building.error().message;
  auto block = block_model(building.value());
  ASSERT_TRUE(block.ok()) << block.error().message;
  EXPECT_NEAR(block->heights.ground, 0.0, 1e-9);
  EXPECT_NEAR(block->heights.roof_min, 5.0, 1e-9);
  EXPECT_NEAR(block->heights.roof_max, 9.0, 1e-9);
  EXPECT_NEAR(block->heights.roof_70p, 9.0, 1e-9);
  EXPECT_NEAR(block->heights.roof_area, 120.0, 1e-9);
  EXPECT_TRUE(kernel::check_shape(block->model.shape).valid());
  EXPECT_EQ(kernel::map_child_shapes(block->model.shape, kernel::ShapeKind::Solid).size(), 1u);
  EXPECT_NEAR(kernel::mass_properties(block->model.shape).volume, 120.0 * 9.0, 1e-6);
}

// LoD1.3 (multi_height_block_model): the same L, each part on the building's ground up to its
// own roof's 70th percentile: 60 m² × 5 m + 60 m² × 9 m.
TEST(BlockModel, MultiHeightBlockKeepsEachRoofPartsHeight) {
  const kernel::CsgModel low = leaf(extrusion_at(rectangle(0, 0, 10, 6), 0.0, 5.0));
  const kernel::CsgModel high = leaf(extrusion_at(rectangle(10, 0, 16, 10), 1.0, 8.0));
  auto building = kernel::csg_combine({low, high}, kernel::BooleanOp::Fuse);
  ASSERT_TRUE(building.ok()) << building.error().message;
  auto levels = multi_height_block_model(building.value());
  ASSERT_TRUE(levels.ok()) << levels.error().message;
  EXPECT_NEAR(levels->heights.roof_70p, 9.0, 1e-9);  // the building's, as LoD1.2's
  EXPECT_TRUE(kernel::check_shape(levels->model.shape).valid());
  EXPECT_EQ(kernel::map_child_shapes(levels->model.shape, kernel::ShapeKind::Solid).size(), 1u);
  EXPECT_NEAR(kernel::mass_properties(levels->model.shape).volume, 60.0 * 5.0 + 60.0 * 9.0, 1e-6);
}

// Parts less than a level step apart are one level, at the 70th percentile of their roofs
// together (half the roof at 5 m, half at 5.3 m: 5.3 m); a larger step keeps them apart.
TEST(BlockModel, MultiHeightBlockMergesPartsWithinALevelStep) {
  const kernel::CsgModel a = leaf(extrusion_at(rectangle(0, 0, 10, 6), 0.0, 5.0));
  const kernel::CsgModel b = leaf(extrusion_at(rectangle(10, 0, 20, 6), 0.0, 5.3));
  auto building = kernel::csg_combine({a, b}, kernel::BooleanOp::Fuse);
  ASSERT_TRUE(building.ok()) << building.error().message;
  auto merged = multi_height_block_model(building.value());
  ASSERT_TRUE(merged.ok()) << merged.error().message;
  EXPECT_NEAR(kernel::mass_properties(merged->model.shape).volume, 120.0 * 5.3, 1e-6);
  BlockModelOptions fine;
  fine.level_step = 0.2;
  auto apart = multi_height_block_model(building.value(), fine);
  ASSERT_TRUE(apart.ok()) << apart.error().message;
  EXPECT_NEAR(kernel::mass_properties(apart->model.shape).volume, 60.0 * 5.0 + 60.0 * 5.3, 1e-6);
  EXPECT_TRUE(kernel::check_shape(apart->model.shape).valid());
}

// A row of six houses, three at 5 m and three at 8 m in turn except for two neighbours at 8 m:
// LoD1.3 fuses one prism per level and connected piece (their walls joined in the plane), not
// one per house: five prisms, the exact volume, one valid solid.
TEST(BlockModel, MultiHeightBlockFusesOnePrismPerLevelPiece) {
  const double heights[] = {5.0, 8.0, 8.0, 5.0, 8.0, 5.0};
  std::vector<kernel::CsgModel> houses;
  double volume = 0.0;
  for (int k = 0; k < 6; ++k) {
    houses.push_back(leaf(extrusion_at(rectangle(6.0 * k, 0, 6.0 * (k + 1), 9), 0.0, heights[k])));
    volume += 54.0 * heights[k];
  }
  auto building = kernel::csg_combine(houses, kernel::BooleanOp::Fuse);
  ASSERT_TRUE(building.ok()) << building.error().message;
  auto levels = multi_height_block_model(building.value());
  ASSERT_TRUE(levels.ok()) << levels.error().message;
  EXPECT_TRUE(kernel::check_shape(levels->model.shape).valid());
  EXPECT_EQ(kernel::map_child_shapes(levels->model.shape, kernel::ShapeKind::Solid).size(), 1u);
  EXPECT_NEAR(kernel::mass_properties(levels->model.shape).volume, volume, 1e-6);
  std::size_t prisms = 0;
  for (const auto& node : levels->model.nodes) {
    prisms += node.kind == kernel::CsgNodeKind::Primitive ? 1 : 0;
  }
  EXPECT_EQ(prisms, 5u);  // 5 m: houses 0, 3, 5; 8 m: houses 1-2 (one piece), 4
}

// One roof part: LoD1.3 is LoD1.2's block.
TEST(BlockModel, MultiHeightBlockOfOnePartIsTheBlock) {
  const kernel::CsgModel house = leaf(test::gable_house());
  auto levels = multi_height_block_model(house);
  ASSERT_TRUE(levels.ok()) << levels.error().message;
  EXPECT_NEAR(kernel::mass_properties(levels->model.shape).volume, 60.0 * 7.1, 1e-6);
  PrimitiveSpec column;
  column.type = kernel::PrimitiveType::Cylinder;
  column.radius = 0.2;
  column.height = 3.0;
  auto curved = multi_height_block_model(leaf(column));
  ASSERT_FALSE(curved.ok());
  EXPECT_EQ(curved.error().code, kernel::ErrorCode::InvalidArgument);
}

// A courtyard building: the footprint keeps its hole.
TEST(BlockModel, ACourtyardStaysAHole) {
  PrimitiveSpec s = extrusion_at(rectangle(0, 0, 20, 20), 0.0, 6.0);
  s.holes.push_back(rectangle(5, 5, 15, 15));
  auto block = block_model(leaf(s));
  ASSERT_TRUE(block.ok()) << block.error().message;
  EXPECT_NEAR(block->heights.roof_70p, 6.0, 1e-9);
  EXPECT_NEAR(kernel::mass_properties(block->model.shape).volume, 300.0 * 6.0, 1e-6);
}

TEST(BlockModel, OnlyBuildingsOfPlanarPrimitivesHaveOne) {
  PrimitiveSpec column;
  column.type = kernel::PrimitiveType::Cylinder;
  column.radius = 0.2;
  column.height = 3.0;
  auto block = block_model(leaf(column));
  ASSERT_FALSE(block.ok());
  EXPECT_EQ(block.error().code, kernel::ErrorCode::InvalidArgument);
  EXPECT_NE(block.error().message.find("cylinder"), std::string::npos) << block.error().message;

  EXPECT_FALSE(block_model(kernel::CsgModel{}).ok());
}

// A house fitted as an extrusion of its section along the ridge (lying, not standing): its
// footprint is the faces that look down, the block stands on it.
TEST(BlockModel, AnExtrusionLyingAlongItsRidgeHasABlockToo) {
  // The section 6 m wide in (x, local y), eaves at 3 m and ridge at 5 m; swept 10 m along -y.
  PrimitiveSpec lying;
  lying.type = kernel::PrimitiveType::Extrusion;
  lying.profile = {{0, 0}, {6, 0}, {6, 3}, {3, 5}, {0, 3}};
  lying.height = 10.0;
  lying.placement = kernel::Location::rotation(Vec3::Zero(), Vec3::UnitX(), 0.5 * M_PI);
  auto block = block_model(leaf(lying));
  ASSERT_TRUE(block.ok()) << block.error().message;
  EXPECT_NEAR(block->heights.ground, 0.0, 1e-9);
  EXPECT_NEAR(block->heights.roof_min, 3.0, 1e-9);
  EXPECT_NEAR(block->heights.roof_max, 5.0, 1e-9);
  EXPECT_NEAR(block->heights.roof_70p, 3.0 + 0.7 * 2.0, 1e-9);
  EXPECT_NEAR(kernel::mass_properties(block->model.shape).volume, 60.0 * 4.4, 1e-6);
}

// A shed fitted from a real Delft tile (regression): its walls lean out by 5 mm over 2 m, so
// they look down a little. Their projections, 5 mm strips, are no footprint: the block stands
// on the bottom alone (with them it had slivers that crossed themselves once quantised).
TEST(BlockModel, WallsLeaningOutByMillimetresAddNoSliversToTheFootprint) {
  PrimitiveSpec shed;
  shed.type = kernel::PrimitiveType::Extrusion;
  shed.profile = {{0, 0}, {3, 0}, {3.005, 2}, {-0.005, 2}};  // the section, walls leaning out
  shed.height = 4.0;
  shed.placement = kernel::Location::rotation(Vec3::Zero(), Vec3::UnitX(), 0.5 * M_PI);
  auto block = block_model(leaf(shed));
  ASSERT_TRUE(block.ok()) << block.error().message;
  EXPECT_EQ(block->model.nodes.size(), 1u);  // one footprint piece, no fuse
  EXPECT_NEAR(kernel::mass_properties(block->model.shape).volume, 12.0 * block->heights.roof_70p,
              1e-6);
}

// A house fitted lying along its ridge whose axis is 0.17° off level (a real Delft tile, cut
// into 37 m tiles: regression): one gable wall looks down a little, its projection a strip
// tapering from 15 mm under the ridge to nothing at the ground, 12 mm wide on average. It is
// no footprint either: with it, the LoD1.3 block kept an 8 mm chamfer at two corners whose
// triangles val3dity found crossing each other once the coordinates were rounded to
// millimetres.
TEST(BlockModel, AGableWallLeaningOutByMillimetresAddsNoSliverToTheFootprint) {
  PrimitiveSpec lying;
  lying.type = kernel::PrimitiveType::Extrusion;
  lying.profile = {{0, 0}, {6, 0}, {6, 3}, {3, 5}, {0, 3}};
  lying.height = 10.0;
  lying.placement = kernel::Location::rotation(Vec3::Zero(), Vec3::UnitX(), 0.5 * M_PI + 0.003);
  for (const bool levels : {false, true}) {
    auto block = levels ? multi_height_block_model(leaf(lying)) : block_model(leaf(lying));
    ASSERT_TRUE(block.ok()) << block.error().message;
    EXPECT_EQ(block->model.nodes.size(), 1u) << levels;  // the bottom alone, no fuse
    EXPECT_TRUE(kernel::check_shape(block->model.shape).valid()) << levels;
  }
}

}  // namespace
}  // namespace csgtile::assembly
