// The config's `fit:` section (with run.seed, run.threads and kernel.linear_tolerance) →
// geo/fit's options.

#include "city/fit_tile.h"

namespace csgtile::worker::city {

fit::FitPipelineOptions fit_options(const config::Config& config) {
  const config::FitConfig& c = config.fit;
  fit::FitPipelineOptions o;
  o.classes.keep.clear();
  for (int k : c.classes.keep) o.classes.keep.push_back(static_cast<std::uint8_t>(k));
  o.classes.drop.clear();
  for (int k : c.classes.drop) o.classes.drop.push_back(static_cast<std::uint8_t>(k));
  o.outliers.enabled = c.outliers.enabled;
  o.outliers.neighbours = c.outliers.neighbours;
  o.outliers.std_ratio = c.outliers.std_ratio;
  o.voxel.size = c.voxel.size;
  o.normals.neighbours = c.normals.neighbours;
  o.normals.sharp = c.normals.sharp;
  o.ground.enabled = c.ground.enabled;
  o.ground.use_classification = c.ground.use_classification;
  o.ground.cell = c.ground.cell;
  o.ground.window = c.ground.window;
  o.ground.height = c.ground.height;
  o.ground.slope = c.ground.slope;
  o.ground.max_height = c.ground.max_height;
  o.vegetation.enabled = c.vegetation.enabled;
  o.vegetation.curvature = c.vegetation.curvature;
  o.vegetation.radius = c.vegetation.radius;
  o.vegetation.share = c.vegetation.share;
  o.clusters.tolerance = c.clusters.tolerance;
  o.clusters.min_points = c.clusters.min_points;
  o.regions.enabled = c.regions.enabled;
  o.regions.neighbours = c.regions.neighbours;
  o.regions.smoothness_deg = c.regions.smoothness_deg;
  o.regions.curvature = c.regions.curvature;
  o.regions.min_points = c.regions.min_points;
  o.ransac.epsilon = c.ransac.epsilon;
  o.ransac.normal_deviation_deg = c.ransac.normal_deviation_deg;
  o.ransac.cluster_epsilon = c.ransac.cluster_epsilon;
  o.ransac.min_points = c.ransac.min_points;
  o.ransac.probability = c.ransac.probability;
  o.ransac.max_radius = c.ransac.max_radius;
  o.ransac.max_candidates = c.ransac.max_candidates;
  o.ransac.relabel = c.ransac.relabel;
  o.ransac.by_evidence = c.ransac.by_evidence;
  o.ransac.edges_to_smaller = c.ransac.edges_to_smaller;
  o.ransac.cluster_scale = c.ransac.cluster_scale;
  o.ransac.merge_same_surface = c.ransac.merge_same_surface;
  o.ransac.seed = config.run.seed;
  for (int t = 0; t < fit::kShapeTypeCount; ++t) {
    const std::string name = fit::shape_type_name(static_cast<fit::ShapeType>(t));
    bool on = false;
    for (const std::string& s : c.ransac.shapes) on = on || s == name;
    o.ransac.shapes[static_cast<std::size_t>(t)] = on;
  }
  o.primitives.boxes = c.primitives.boxes;
  o.primitives.max_box_depth = c.primitives.max_box_depth;
  o.primitives.min_box_thickness = c.primitives.min_box_thickness;
  o.primitives.min_seed_coverage = c.primitives.min_seed_coverage;
  o.primitives.angle_tolerance_deg = c.primitives.angle_tolerance_deg;
  o.primitives.min_angular_span_deg = c.primitives.min_angular_span_deg;
  o.primitives.min_building_height = c.primitives.min_building_height;
  o.primitives.min_building_width = c.primitives.min_building_width;
  o.primitives.extrusions = c.primitives.extrusions;
  o.primitives.revolutions = c.primitives.revolutions;
  o.primitives.roof_parts = c.primitives.roof_parts;
  o.primitives.roof_partition = c.primitives.roof_partition;
  o.primitives.split_houses = c.primitives.split_houses;
  o.primitives.min_house_area = c.primitives.min_house_area;
  o.primitives.blocks = c.primitives.blocks;
  o.primitives.min_curved_coverage = c.primitives.min_curved_coverage;
  o.primitives.max_overreach = c.primitives.max_overreach;
  o.primitives.linear_tolerance = config.kernel.linear_tolerance;
  o.threads = config.run.threads;  // the regions on run.threads cores
  return o;
}

}  // namespace csgtile::worker::city
