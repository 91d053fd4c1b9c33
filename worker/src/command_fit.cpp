// `csgtile fit INPUT [--config C] --out primitives.json [--json] [--seed N] [--crs EPSG:N]`:
// reads a LAS/PLY/PCD/XYZ point cloud, segments it, fits primitives (geo/fit.h, geo/segment.h)
// and writes them in the scene format, in the tile-local frame (origin = the LAS offset, or
// the floor of the smallest x and y for other formats) with the CRS and the seed. The file
// holds no timings: the same input, config and seed give the same bytes. Counts per type,
// unassigned points, rejections with reasons and per-stage timings go to stdout.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "commands.h"
#include "csgtile/geo/crs.h"
#include "csgtile/geo/las.h"
#include "csgtile/geo/point_reader.h"
#include "csgtile/geo/scene.h"
#include "csgtile/geo/segment.h"
#include "csgtile/worker/errors.h"

namespace csgtile::worker::detail {

namespace {

using Json = nlohmann::ordered_json;

struct FitCommand {
  std::string input;
  std::string config;
  std::string out;
  std::string crs;
  std::uint64_t seed = 1;
  bool seed_given = false;
  bool json = false;
};

// Reads one number or flag of the fit config into `target`, naming the key on errors.
template <class T>
bool take(const nlohmann::json& object, const std::string& path, const char* key, T& target,
          std::string& error) {
  const auto it = object.find(key);
  if (it == object.end()) return true;
  try {
    target = it->get<T>();
  } catch (const nlohmann::json::exception&) {
    error = path + "." + key + ": wrong type";
    return false;
  }
  return true;
}

// The fit config: a JSON object whose sections mirror geo::FitPipelineOptions (every key
// optional; unknown keys are errors naming their path).
bool read_fit_config(const std::string& file, geo::FitPipelineOptions& o, std::string& error) {
  std::ifstream in(file, std::ios::binary);
  if (!in) {
    error = file + ": cannot read";
    return false;
  }
  nlohmann::json doc;
  try {
    doc = nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    error = file + ": not JSON: " + e.what();
    return false;
  }
  if (!doc.is_object()) {
    error = file + ": the fit config must be a JSON object";
    return false;
  }
  struct Section {
    const char* name;
    std::vector<const char*> keys;
  };
  const std::vector<Section> known = {
      {"outliers", {"enabled", "neighbours", "std_ratio"}},
      {"voxel", {"size"}},
      {"normals", {"neighbours"}},
      {"ground", {"enabled", "use_classification", "cell", "window", "height"}},
      {"clusters", {"tolerance", "min_points"}},
      {"ransac",
       {"epsilon", "normal_deviation_deg", "cluster_epsilon", "min_points", "probability",
        "max_radius", "seed", "plane", "sphere", "cylinder", "cone", "torus", "max_candidates"}},
      {"primitives",
       {"boxes", "max_box_depth", "min_box_thickness", "min_seed_coverage", "angle_tolerance_deg"}},
  };
  for (const auto& [name, value] : doc.items()) {
    const auto section =
        std::find_if(known.begin(), known.end(), [&](const Section& s) { return name == s.name; });
    if (section == known.end()) {
      error = file + ": unknown key \"" + name + "\"";
      return false;
    }
    if (!value.is_object()) {
      error = file + ": " + name + ": must be an object";
      return false;
    }
    for (const auto& [key, ignored] : value.items()) {
      if (std::find_if(section->keys.begin(), section->keys.end(),
                       [&](const char* k) { return key == k; }) == section->keys.end()) {
        error = file + ": unknown key \"" + name + "." + key + "\"";
        return false;
      }
    }
  }
  const nlohmann::json empty = nlohmann::json::object();
  auto sec = [&](const char* name) -> const nlohmann::json& {
    const auto it = doc.find(name);
    return it == doc.end() ? empty : *it;
  };
  const auto& ransac = sec("ransac");
  bool ok =
      take(sec("outliers"), "outliers", "enabled", o.outliers.enabled, error) &&
      take(sec("outliers"), "outliers", "neighbours", o.outliers.neighbours, error) &&
      take(sec("outliers"), "outliers", "std_ratio", o.outliers.std_ratio, error) &&
      take(sec("voxel"), "voxel", "size", o.voxel.size, error) &&
      take(sec("normals"), "normals", "neighbours", o.normals.neighbours, error) &&
      take(sec("ground"), "ground", "enabled", o.ground.enabled, error) &&
      take(sec("ground"), "ground", "use_classification", o.ground.use_classification, error) &&
      take(sec("ground"), "ground", "cell", o.ground.cell, error) &&
      take(sec("ground"), "ground", "window", o.ground.window, error) &&
      take(sec("ground"), "ground", "height", o.ground.height, error) &&
      take(sec("clusters"), "clusters", "tolerance", o.clusters.tolerance, error) &&
      take(sec("clusters"), "clusters", "min_points", o.clusters.min_points, error) &&
      take(ransac, "ransac", "epsilon", o.ransac.epsilon, error) &&
      take(ransac, "ransac", "normal_deviation_deg", o.ransac.normal_deviation_deg, error) &&
      take(ransac, "ransac", "cluster_epsilon", o.ransac.cluster_epsilon, error) &&
      take(ransac, "ransac", "min_points", o.ransac.min_points, error) &&
      take(ransac, "ransac", "probability", o.ransac.probability, error) &&
      take(ransac, "ransac", "max_radius", o.ransac.max_radius, error) &&
      take(ransac, "ransac", "seed", o.ransac.seed, error) &&
      take(ransac, "ransac", "max_candidates", o.ransac.max_candidates, error) &&
      take(sec("primitives"), "primitives", "boxes", o.primitives.boxes, error) &&
      take(sec("primitives"), "primitives", "max_box_depth", o.primitives.max_box_depth, error) &&
      take(sec("primitives"), "primitives", "min_box_thickness", o.primitives.min_box_thickness,
           error) &&
      take(sec("primitives"), "primitives", "min_seed_coverage", o.primitives.min_seed_coverage,
           error) &&
      take(sec("primitives"), "primitives", "angle_tolerance_deg", o.primitives.angle_tolerance_deg,
           error);
  const char* types[] = {"plane", "sphere", "cylinder", "cone", "torus"};
  for (std::size_t t = 0; ok && t < 5; ++t) {
    bool enabled = o.ransac.shapes[t];
    ok = take(ransac, "ransac", types[t], enabled, error);
    o.ransac.shapes[t] = enabled;
  }
  if (!ok) error = file + ": " + error;
  return ok;
}

double since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

int run_fit(const FitCommand& c) {
  const auto start = std::chrono::steady_clock::now();
  Json out;
  out["input"] = c.input;
  auto fail = [&](ErrorCode code, const std::string& message) {
    if (c.json) {
      out["error"] = std::string(error_info(code).name) + ": " + message;
      std::cout << out.dump() << "\n";
    } else {
      std::fprintf(stderr, "csgtile fit: %s\n", message.c_str());
    }
    return error_info(code).exit_code;
  };

  geo::FitPipelineOptions options;
  if (!c.config.empty()) {
    std::string error;
    if (!read_fit_config(c.config, options, error)) return fail(ErrorCode::ConfigInvalid, error);
  }
  if (c.seed_given) options.ransac.seed = c.seed;

  // Read every point (the pipeline needs the whole tile), in the local frame.
  auto opened = geo::open_point_file(c.input);
  if (!opened.ok()) return fail(from_kernel(opened.error().code), opened.error().message);
  geo::PointReader& reader = *opened.value();
  std::array<double, 3> origin{0.0, 0.0, 0.0};
  std::string crs_text;
  const auto* las = dynamic_cast<const geo::LasReader*>(&reader);
  if (las != nullptr) {
    origin = las->header().offset;
    auto crs = geo::las_file_crs(las->crs(), c.crs);
    if (crs.ok()) {
      const geo::Crs& v = crs.value();
      if (v.epsg != 0) {
        crs_text = "EPSG:" + std::to_string(v.epsg);
        if (v.vertical && v.vertical->epsg != 0) crs_text += "+" + std::to_string(v.vertical->epsg);
      } else {
        crs_text = geo::crs_to_wkt1(v);
      }
    }
  } else if (!c.crs.empty()) {
    auto crs = geo::crs_from_config(c.crs);
    if (!crs.ok()) return fail(ErrorCode::Usage, "--crs: " + crs.error().message);
    crs_text = c.crs;
  }
  std::vector<kernel::Vec3> raw;
  std::vector<std::uint8_t> classes;
  const bool has_classes = reader.info().fields.classification;
  geo::PointBatch batch;
  for (;;) {
    auto n = reader.read(batch, 1 << 16);
    if (!n.ok()) return fail(from_kernel(n.error().code), n.error().message);
    if (n.value() == 0) break;
    for (const auto& p : batch.points) {
      raw.emplace_back(p.x, p.y, p.z);
      if (has_classes) classes.push_back(p.classification);
    }
  }
  if (las == nullptr && !raw.empty()) {
    double x = INFINITY, y = INFINITY;
    for (const auto& p : raw) {
      if (!p.allFinite()) continue;
      x = std::min(x, p.x());
      y = std::min(y, p.y());
    }
    if (std::isfinite(x)) origin = {std::floor(x), std::floor(y), 0.0};
  }
  const kernel::Vec3 o(origin[0], origin[1], origin[2]);
  for (auto& p : raw) p -= o;
  const double read_seconds = since(start);

  auto fitted = geo::fit_point_cloud(raw, classes, options);
  if (!fitted.ok()) return fail(ErrorCode::ConfigInvalid, fitted.error().message);
  const geo::FitOutput& f = fitted.value();

  geo::Scene scene;
  scene.name = std::filesystem::path(c.input).stem().string();
  scene.seed = options.ransac.seed;
  if (!crs_text.empty() || las != nullptr) scene.frame = geo::SceneFrame{crs_text, origin};
  scene.primitives = f.primitives;
  const std::string text = geo::scene_to_json(scene);
  {
    const std::filesystem::path target(c.out);
    const std::filesystem::path temp = target.string() + ".tmp";
    std::ofstream file(temp, std::ios::binary | std::ios::trunc);
    file << text;
    file.close();
    if (!file) return fail(ErrorCode::Io, c.out + ": cannot write");
    std::error_code ec;
    std::filesystem::rename(temp, target, ec);
    if (ec) return fail(ErrorCode::Io, c.out + ": " + ec.message());
  }

  Json per_type = Json::object();
  for (int t = 0; t < kernel::kPrimitiveTypeCount; ++t) {
    per_type[kernel::primitive_type_name(static_cast<kernel::PrimitiveType>(t))] =
        f.per_type[static_cast<std::size_t>(t)];
  }
  Json rejected = Json::array();
  std::map<std::string, long long> reasons;
  for (const auto& r : f.rejected) {
    rejected.push_back(Json{{"what", r.what}, {"reason", r.reason}, {"points", r.points}});
    reasons[r.reason] += 1;
  }
  Json seconds = Json::object();
  seconds["read"] = read_seconds;
  for (const auto& [stage, s] : f.seconds) seconds[stage] = s;
  seconds["total"] = since(start);
  out["points"] = f.input_points;
  out["ground_points"] = f.ground_points;
  out["outlier_points"] = f.outlier_points;
  out["fitted_points"] = f.fitted_points;
  out["small_cluster_points"] = f.small_cluster_points;
  out["assigned_points"] = f.assigned_points;
  out["unassigned_points"] = f.unassigned_points;
  out["regions"] = f.regions;
  out["cluster_tolerance"] = f.cluster_tolerance;
  Json regions = Json::array();
  for (const auto& r : f.region_stats) {
    regions.push_back(Json{{"points", r.points},
                           {"spacing", r.spacing},
                           {"cluster_epsilon", r.cluster_epsilon},
                           {"shapes", r.shapes},
                           {"primitives", r.primitives},
                           {"candidates", r.candidates}});
  }
  out["region_stats"] = regions;
  out["candidates"] = f.candidates;
  out["primitives"] = static_cast<long long>(f.primitives.size());
  out["per_type"] = per_type;
  out["rejected"] = rejected;
  out["seed"] = options.ransac.seed;
  out["out"] = c.out;
  out["seconds"] = seconds;
  out["error"] = nullptr;
  if (c.json) {
    std::cout << out.dump() << "\n";
    return 0;
  }
  std::printf("%-20s%lld (ground %lld, outliers %lld)\n", "points", f.input_points, f.ground_points,
              f.outlier_points);
  std::printf("%-20s%lld in %d regions\n", "fitted points", f.fitted_points, f.regions);
  std::printf("%-20s%zu\n", "primitives", f.primitives.size());
  for (int t = 0; t < kernel::kPrimitiveTypeCount; ++t) {
    const long long n = f.per_type[static_cast<std::size_t>(t)];
    if (n > 0) {
      std::printf("  %-18s%lld\n",
                  kernel::primitive_type_name(static_cast<kernel::PrimitiveType>(t)), n);
    }
  }
  std::printf("%-20s%lld\n", "unassigned points", f.unassigned_points);
  std::printf("%-20s%zu\n", "rejected", f.rejected.size());
  for (const auto& [reason, n] : reasons) std::printf("  %5lld  %s\n", n, reason.c_str());
  for (const auto& [stage, s] : seconds.items()) {
    std::printf("%-20s%.3f s\n", ("time " + stage).c_str(), s.get<double>());
  }
  std::printf("%-20s%s\n", "out", c.out.c_str());
  return 0;
}

}  // namespace

void register_fit(CLI::App& app, Action& action) {
  auto* cmd = app.add_subcommand(
      "fit",
      "Segment a LAS/PLY/PCD/XYZ point cloud and fit primitives (boxes, cylinders, cones, "
      "spheres, tori) to it; writes them as scene JSON in the tile-local frame");
  auto c = std::make_shared<FitCommand>();
  cmd->add_option("INPUT", c->input, "Point cloud (LAS, PLY, PCD or XYZ text)")->required();
  cmd->add_option("--out", c->out, "Scene JSON of the fitted primitives to write")->required();
  cmd->add_option("--config", c->config,
                  "Fit options as JSON: sections outliers, voxel, normals, ground, clusters, "
                  "ransac, primitives (see geo/segment.h)");
  cmd->add_option("--seed", c->seed, "Seed of the RANSAC (overrides the config's)");
  cmd->add_option("--crs", c->crs, "CRS to assume when the file has none (EPSG:code[+vertical])");
  cmd->add_flag("--json", c->json, "Print one JSON object");
  cmd->callback([&action, c, cmd] {
    c->seed_given = cmd->count("--seed") > 0;
    action = [c] { return run_fit(*c); };
  });
}

}  // namespace csgtile::worker::detail
