// The `fit:` section: document → FitConfig and back (config.cpp does the other sections).

#include "document.h"

namespace csgtile::config::detail {
namespace {

using nlohmann::json;

/// Reads `fit.<section>.<key>` into `target` when present (the document is valid).
template <typename T>
void take(const json& fit, const char* section, const char* key, T& target) {
  const auto s = fit.find(section);
  if (s == fit.end() || !s->is_object()) return;
  const auto k = s->find(key);
  if (k != s->end()) target = k->template get<T>();
}

}  // namespace

void read_fit(const json& document, FitConfig& fit) {
  const auto found = document.find("fit");
  if (found == document.end() || !found->is_object()) return;
  const json& f = *found;
  take(f, "classes", "keep", fit.classes.keep);
  take(f, "classes", "drop", fit.classes.drop);
  take(f, "outliers", "enabled", fit.outliers.enabled);
  take(f, "outliers", "neighbours", fit.outliers.neighbours);
  take(f, "outliers", "std_ratio", fit.outliers.std_ratio);
  take(f, "voxel", "size", fit.voxel.size);
  take(f, "normals", "neighbours", fit.normals.neighbours);
  take(f, "normals", "sharp", fit.normals.sharp);
  take(f, "ground", "enabled", fit.ground.enabled);
  take(f, "ground", "use_classification", fit.ground.use_classification);
  take(f, "ground", "cell", fit.ground.cell);
  take(f, "ground", "window", fit.ground.window);
  take(f, "ground", "height", fit.ground.height);
  take(f, "ground", "slope", fit.ground.slope);
  take(f, "ground", "max_height", fit.ground.max_height);
  take(f, "vegetation", "enabled", fit.vegetation.enabled);
  take(f, "vegetation", "curvature", fit.vegetation.curvature);
  take(f, "vegetation", "radius", fit.vegetation.radius);
  take(f, "vegetation", "share", fit.vegetation.share);
  take(f, "clusters", "tolerance", fit.clusters.tolerance);
  take(f, "clusters", "min_points", fit.clusters.min_points);
  take(f, "regions", "enabled", fit.regions.enabled);
  take(f, "regions", "neighbours", fit.regions.neighbours);
  take(f, "regions", "smoothness_deg", fit.regions.smoothness_deg);
  take(f, "regions", "curvature", fit.regions.curvature);
  take(f, "regions", "min_points", fit.regions.min_points);
  take(f, "ransac", "epsilon", fit.ransac.epsilon);
  take(f, "ransac", "normal_deviation_deg", fit.ransac.normal_deviation_deg);
  take(f, "ransac", "cluster_epsilon", fit.ransac.cluster_epsilon);
  take(f, "ransac", "min_points", fit.ransac.min_points);
  take(f, "ransac", "probability", fit.ransac.probability);
  take(f, "ransac", "max_radius", fit.ransac.max_radius);
  take(f, "ransac", "shapes", fit.ransac.shapes);
  take(f, "ransac", "max_candidates", fit.ransac.max_candidates);
  take(f, "ransac", "relabel", fit.ransac.relabel);
  take(f, "ransac", "by_evidence", fit.ransac.by_evidence);
  take(f, "ransac", "edges_to_smaller", fit.ransac.edges_to_smaller);
  take(f, "ransac", "cluster_scale", fit.ransac.cluster_scale);
  take(f, "ransac", "merge_same_surface", fit.ransac.merge_same_surface);
  take(f, "primitives", "boxes", fit.primitives.boxes);
  take(f, "primitives", "max_box_depth", fit.primitives.max_box_depth);
  take(f, "primitives", "min_box_thickness", fit.primitives.min_box_thickness);
  take(f, "primitives", "min_seed_coverage", fit.primitives.min_seed_coverage);
  take(f, "primitives", "angle_tolerance_deg", fit.primitives.angle_tolerance_deg);
  take(f, "primitives", "min_angular_span_deg", fit.primitives.min_angular_span_deg);
  take(f, "primitives", "min_building_height", fit.primitives.min_building_height);
  take(f, "primitives", "min_building_width", fit.primitives.min_building_width);
  take(f, "primitives", "extrusions", fit.primitives.extrusions);
  take(f, "primitives", "revolutions", fit.primitives.revolutions);
  take(f, "primitives", "roof_parts", fit.primitives.roof_parts);
  take(f, "primitives", "roof_partition", fit.primitives.roof_partition);
  take(f, "primitives", "split_houses", fit.primitives.split_houses);
  take(f, "primitives", "min_house_area", fit.primitives.min_house_area);
  take(f, "primitives", "blocks", fit.primitives.blocks);
  take(f, "primitives", "min_curved_coverage", fit.primitives.min_curved_coverage);
  take(f, "primitives", "max_overreach", fit.primitives.max_overreach);
}

json fit_to_json(const FitConfig& fit) {
  json out;
  out["classes"] = {{"keep", fit.classes.keep}, {"drop", fit.classes.drop}};
  out["outliers"] = {{"enabled", fit.outliers.enabled},
                     {"neighbours", fit.outliers.neighbours},
                     {"std_ratio", fit.outliers.std_ratio}};
  out["voxel"] = {{"size", fit.voxel.size}};
  out["normals"] = {{"neighbours", fit.normals.neighbours}, {"sharp", fit.normals.sharp}};
  out["ground"] = {{"enabled", fit.ground.enabled},
                   {"use_classification", fit.ground.use_classification},
                   {"cell", fit.ground.cell},
                   {"window", fit.ground.window},
                   {"height", fit.ground.height},
                   {"slope", fit.ground.slope},
                   {"max_height", fit.ground.max_height}};
  out["vegetation"] = {{"enabled", fit.vegetation.enabled},
                       {"curvature", fit.vegetation.curvature},
                       {"radius", fit.vegetation.radius},
                       {"share", fit.vegetation.share}};
  out["clusters"] = {{"tolerance", fit.clusters.tolerance},
                     {"min_points", fit.clusters.min_points}};
  out["regions"] = {{"enabled", fit.regions.enabled},
                    {"neighbours", fit.regions.neighbours},
                    {"smoothness_deg", fit.regions.smoothness_deg},
                    {"curvature", fit.regions.curvature},
                    {"min_points", fit.regions.min_points}};
  out["ransac"] = {{"epsilon", fit.ransac.epsilon},
                   {"normal_deviation_deg", fit.ransac.normal_deviation_deg},
                   {"cluster_epsilon", fit.ransac.cluster_epsilon},
                   {"min_points", fit.ransac.min_points},
                   {"probability", fit.ransac.probability},
                   {"max_radius", fit.ransac.max_radius},
                   {"shapes", fit.ransac.shapes},
                   {"max_candidates", fit.ransac.max_candidates},
                   {"relabel", fit.ransac.relabel},
                   {"by_evidence", fit.ransac.by_evidence},
                   {"edges_to_smaller", fit.ransac.edges_to_smaller},
                   {"cluster_scale", fit.ransac.cluster_scale},
                   {"merge_same_surface", fit.ransac.merge_same_surface}};
  out["primitives"] = {{"boxes", fit.primitives.boxes},
                       {"max_box_depth", fit.primitives.max_box_depth},
                       {"min_box_thickness", fit.primitives.min_box_thickness},
                       {"min_seed_coverage", fit.primitives.min_seed_coverage},
                       {"angle_tolerance_deg", fit.primitives.angle_tolerance_deg},
                       {"min_angular_span_deg", fit.primitives.min_angular_span_deg},
                       {"min_building_height", fit.primitives.min_building_height},
                       {"min_building_width", fit.primitives.min_building_width},
                       {"extrusions", fit.primitives.extrusions},
                       {"revolutions", fit.primitives.revolutions},
                       {"roof_parts", fit.primitives.roof_parts},
                       {"roof_partition", fit.primitives.roof_partition},
                       {"split_houses", fit.primitives.split_houses},
                       {"min_house_area", fit.primitives.min_house_area},
                       {"blocks", fit.primitives.blocks},
                       {"min_curved_coverage", fit.primitives.min_curved_coverage},
                       {"max_overreach", fit.primitives.max_overreach}};
  return out;
}

}  // namespace csgtile::config::detail
