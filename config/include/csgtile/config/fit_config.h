#pragma once
/// \file
/// `fit:` — segmentation and fitting options, as plain values. They mirror geo/fit's option
/// structs (csgtile/fit/segment.h), which the worker fills from them in one place; a test
/// checks that the defaults here are geo/fit's defaults.

#include <cstdint>
#include <string>
#include <vector>

namespace csgtile::config {

struct FitClassesConfig {
  std::vector<int> keep{6};  ///< ASPRS classes fitted when the tile carries any of them
  /// Classes never fitted on a classified tile without a keep class.
  std::vector<int> drop{3, 4, 5, 7, 9, 18};
  bool operator==(const FitClassesConfig&) const = default;
};

struct FitOutliersConfig {
  bool enabled = true;
  int neighbours = 12;     ///< 2..1000
  double std_ratio = 3.0;  ///< (0, 100]
  bool operator==(const FitOutliersConfig&) const = default;
};

struct FitVoxelConfig {
  double size = 0.0;  ///< [0, 100]; 0 keeps every point
  bool operator==(const FitVoxelConfig&) const = default;
};

struct FitNormalsConfig {
  int neighbours = 16;  ///< 3..1000
  bool sharp = false;   ///< the normal of the face a point lies on at sharp edges
  bool operator==(const FitNormalsConfig&) const = default;
};

struct FitGroundConfig {
  bool enabled = true;
  bool use_classification = true;
  double cell = 1.0;
  double window = 150.0;
  double height = 0.3;
  double slope = 0.2;
  double max_height = 3.0;
  bool operator==(const FitGroundConfig&) const = default;
};

/// Vegetation on unclassified tiles (fit::VegetationOptions).
struct FitVegetationConfig {
  bool enabled = true;
  double curvature = 0.05;
  double radius = 0.0;  ///< 0: four times the point spacing
  double share = 0.65;
  bool operator==(const FitVegetationConfig&) const = default;
};

struct FitClustersConfig {
  double tolerance = 0.0;  ///< 0: from the spacing
  long long min_points = 40;
  bool operator==(const FitClustersConfig&) const = default;
};

struct FitRegionsConfig {
  bool enabled = false;
  int neighbours = 16;
  double smoothness_deg = 10.0;
  double curvature = 1.0;
  long long min_points = 40;
  bool operator==(const FitRegionsConfig&) const = default;
};

struct FitRansacConfig {
  double epsilon = 0.02;
  double normal_deviation_deg = 25.0;
  double cluster_epsilon = 0.0;  ///< 0: from the spacing
  long long min_points = 40;
  double probability = 0.99;
  double max_radius = 30.0;
  /// Surface types detected: "plane", "sphere", "cylinder", "cone", "torus".
  std::vector<std::string> shapes{"plane", "sphere", "cylinder", "cone", "torus"};
  std::uint64_t max_candidates = 2000000;
  bool relabel = false;           ///< each point to the neighbouring shape it fits best, then refit
  bool by_evidence = false;       ///< shape types chosen by an information criterion
  bool edges_to_smaller = false;  ///< a point on two shapes to the smaller (exact clouds)
  double cluster_scale = 1.0;     ///< times the derived connectivity (cluster_epsilon 0)
  bool merge_same_surface = false;  ///< shapes on one surface with a narrow gap become one
  bool operator==(const FitRansacConfig&) const = default;
};

struct FitPrimitivesConfig {
  bool boxes = true;
  double max_box_depth = 40.0;
  double min_box_thickness = 0.04;
  double min_seed_coverage = 0.6;
  double angle_tolerance_deg = 5.0;
  double min_angular_span_deg = 90.0;
  double min_building_height = 2.0;
  double min_building_width = 1.0;
  bool extrusions = true;
  bool revolutions = true;
  bool roof_parts = true;
  bool roof_partition = true;
  bool split_houses = true;
  double min_house_area = 25.0;
  bool blocks = true;
  double min_curved_coverage = 0.05;
  double max_overreach = 0.25;
  bool operator==(const FitPrimitivesConfig&) const = default;
};

/// Every fit option. The RANSAC's seed is `run.seed`; the kernel tolerance of the solids the
/// fit builds is `kernel.linear_tolerance` (neither is repeated here).
struct FitConfig {
  FitClassesConfig classes;
  FitOutliersConfig outliers;
  FitVoxelConfig voxel;
  FitNormalsConfig normals;
  FitGroundConfig ground;
  FitVegetationConfig vegetation;
  FitClustersConfig clusters;
  FitRegionsConfig regions;
  FitRansacConfig ransac;
  FitPrimitivesConfig primitives;
  bool operator==(const FitConfig&) const = default;
};

}  // namespace csgtile::config
