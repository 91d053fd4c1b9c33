// The config's fit: section reaches geo/fit's options key for key: the default config gives
// the fit's own defaults, and a config that changes every key changes every option.

#include <gtest/gtest.h>

#include "city/fit_tile.h"
#include "csgtile/config/config.h"

namespace csgtile::worker::city {
namespace {

TEST(FitOptions, DefaultConfigGivesTheFitsDefaults) {
  EXPECT_TRUE(fit_options(config::Config{}) == fit::FitPipelineOptions{});
}

TEST(FitOptions, EveryKeyReachesItsOption) {
  const auto loaded = config::load_string(R"(
run: {seed: 77}
kernel: {linear_tolerance: 1.0e-6}
fit:
  classes: {keep: [6, 26], drop: [7]}
  outliers: {enabled: false, neighbours: 9, std_ratio: 2.5}
  voxel: {size: 0.3}
  normals: {neighbours: 11, sharp: true}
  ground: {enabled: false, use_classification: false, cell: 2, window: 50, height: 0.4}
  clusters: {tolerance: 0.7, min_points: 15}
  regions: {enabled: true, neighbours: 12, smoothness_deg: 8, curvature: 0.5, min_points: 20}
  ransac: {epsilon: 0.05, normal_deviation_deg: 20, cluster_epsilon: 0.3, min_points: 25,
           probability: 0.95, max_radius: 12, shapes: [plane, cone], max_candidates: 1000,
           relabel: true, by_evidence: true, edges_to_smaller: true, cluster_scale: 0.6,
           merge_same_surface: true}
  primitives: {boxes: false, max_box_depth: 20, min_box_thickness: 0.1, min_seed_coverage: 0.5,
               angle_tolerance_deg: 3, min_angular_span_deg: 120, min_building_height: 3,
               min_building_width: 2, extrusions: false, revolutions: false,
               min_curved_coverage: 0.2, max_overreach: 0.5, roof_parts: false,
               roof_partition: false, blocks: false}
)",
                                          "every.yaml");
  ASSERT_TRUE(loaded.ok()) << (loaded.problems.empty() ? "" : loaded.problems[0].message);
  const fit::FitPipelineOptions o = fit_options(*loaded.config);
  const fit::FitPipelineOptions d;
  EXPECT_EQ(o.classes.keep, (std::vector<std::uint8_t>{6, 26}));
  EXPECT_EQ(o.classes.drop, (std::vector<std::uint8_t>{7}));
  // Every option differs from its default: no key is dropped on the way.
  EXPECT_FALSE(o.outliers == d.outliers);
  EXPECT_EQ(o.outliers.neighbours, 9);
  EXPECT_EQ(o.outliers.std_ratio, 2.5);
  EXPECT_FALSE(o.outliers.enabled);
  EXPECT_EQ(o.voxel.size, 0.3);
  EXPECT_EQ(o.normals.neighbours, 11);
  EXPECT_TRUE(o.normals.sharp);
  EXPECT_FALSE(o.ground.enabled);
  EXPECT_FALSE(o.ground.use_classification);
  EXPECT_EQ(o.ground.cell, 2.0);
  EXPECT_EQ(o.ground.window, 50.0);
  EXPECT_EQ(o.ground.height, 0.4);
  EXPECT_EQ(o.clusters.tolerance, 0.7);
  EXPECT_EQ(o.clusters.min_points, 15);
  EXPECT_TRUE(o.regions.enabled);
  EXPECT_EQ(o.regions.neighbours, 12);
  EXPECT_EQ(o.regions.smoothness_deg, 8.0);
  EXPECT_EQ(o.regions.curvature, 0.5);
  EXPECT_EQ(o.regions.min_points, 20);
  EXPECT_EQ(o.ransac.epsilon, 0.05);
  EXPECT_EQ(o.ransac.normal_deviation_deg, 20.0);
  EXPECT_EQ(o.ransac.cluster_epsilon, 0.3);
  EXPECT_EQ(o.ransac.min_points, 25);
  EXPECT_EQ(o.ransac.probability, 0.95);
  EXPECT_EQ(o.ransac.max_radius, 12.0);
  EXPECT_EQ(o.ransac.max_candidates, 1000u);
  EXPECT_TRUE(o.ransac.relabel);
  EXPECT_TRUE(o.ransac.by_evidence);
  EXPECT_TRUE(o.ransac.edges_to_smaller);
  EXPECT_EQ(o.ransac.cluster_scale, 0.6);
  EXPECT_TRUE(o.ransac.merge_same_surface);
  EXPECT_EQ(o.ransac.seed, 77u);  // run.seed, the one seed rule
  EXPECT_EQ(o.ransac.shapes,
            (std::array<bool, fit::kShapeTypeCount>{true, false, false, true, false}));
  EXPECT_FALSE(o.primitives.boxes);
  EXPECT_EQ(o.primitives.max_box_depth, 20.0);
  EXPECT_EQ(o.primitives.min_box_thickness, 0.1);
  EXPECT_EQ(o.primitives.min_seed_coverage, 0.5);
  EXPECT_EQ(o.primitives.angle_tolerance_deg, 3.0);
  EXPECT_EQ(o.primitives.min_angular_span_deg, 120.0);
  EXPECT_EQ(o.primitives.min_building_height, 3.0);
  EXPECT_EQ(o.primitives.min_building_width, 2.0);
  EXPECT_FALSE(o.primitives.extrusions);
  EXPECT_FALSE(o.primitives.revolutions);
  EXPECT_EQ(o.primitives.min_curved_coverage, 0.2);
  EXPECT_EQ(o.primitives.max_overreach, 0.5);
  EXPECT_FALSE(o.primitives.roof_parts);
  EXPECT_NE(o.primitives.roof_partition, d.primitives.roof_partition);
  EXPECT_FALSE(o.primitives.roof_partition);
  EXPECT_FALSE(o.primitives.blocks);
  EXPECT_EQ(o.primitives.linear_tolerance, 1.0e-6);  // kernel.linear_tolerance
}

}  // namespace
}  // namespace csgtile::worker::city
