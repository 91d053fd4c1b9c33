// Fit options from JSON and one tile's points → fitted primitives (see fit_tile.h).

#include "city/fit_tile.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <iterator>
#include <optional>
#include <nlohmann/json.hpp>

#include "csgtile/geo/crs.h"
#include "csgtile/geo/las.h"
#include "csgtile/geo/point_reader.h"

namespace csgtile::worker::city {

namespace {

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

}  // namespace

bool parse_fit_options(std::string_view text, const std::string& file, fit::FitPipelineOptions& o,
                       std::string& error) {
  nlohmann::json doc;
  try {
    doc = nlohmann::json::parse(text);
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
      {"classes", {"keep"}},
      {"outliers", {"enabled", "neighbours", "std_ratio"}},
      {"voxel", {"size"}},
      {"normals", {"neighbours"}},
      {"ground", {"enabled", "use_classification", "cell", "window", "height"}},
      {"clusters", {"tolerance", "min_points"}},
      {"regions", {"enabled", "neighbours", "smoothness_deg", "curvature", "min_points"}},
      {"ransac",
       {"epsilon", "normal_deviation_deg", "cluster_epsilon", "min_points", "probability",
        "max_radius", "seed", "plane", "sphere", "cylinder", "cone", "torus", "max_candidates"}},
      {"primitives",
       {"boxes", "max_box_depth", "min_box_thickness", "min_seed_coverage", "angle_tolerance_deg",
        "min_building_width", "extrusions", "revolutions"}},
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
  if (const auto keep = sec("classes").find("keep"); keep != sec("classes").end()) {
    bool valid = keep->is_array();
    o.classes.keep.clear();
    for (std::size_t k = 0; valid && k < keep->size(); ++k) {
      const auto& c = (*keep)[k];
      valid = c.is_number_integer() && c.get<long long>() >= 0 && c.get<long long>() <= 255;
      if (valid) o.classes.keep.push_back(static_cast<std::uint8_t>(c.get<long long>()));
    }
    if (!valid) {
      error = file + ": classes.keep must be a list of class numbers 0..255";
      return false;
    }
  }
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
      take(sec("regions"), "regions", "enabled", o.regions.enabled, error) &&
      take(sec("regions"), "regions", "neighbours", o.regions.neighbours, error) &&
      take(sec("regions"), "regions", "smoothness_deg", o.regions.smoothness_deg, error) &&
      take(sec("regions"), "regions", "curvature", o.regions.curvature, error) &&
      take(sec("regions"), "regions", "min_points", o.regions.min_points, error) &&
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
           error) &&
      take(sec("primitives"), "primitives", "min_building_width", o.primitives.min_building_width,
           error) &&
      take(sec("primitives"), "primitives", "extrusions", o.primitives.extrusions, error) &&
      take(sec("primitives"), "primitives", "revolutions", o.primitives.revolutions, error);
  const char* types[] = {"plane", "sphere", "cylinder", "cone", "torus"};
  for (std::size_t t = 0; ok && t < 5; ++t) {
    bool enabled = o.ransac.shapes[t];
    ok = take(ransac, "ransac", types[t], enabled, error);
    o.ransac.shapes[t] = enabled;
  }
  if (!ok) error = file + ": " + error;
  return ok;
}


bool read_fit_options(const std::string& file, fit::FitPipelineOptions& options, std::string& text,
                      std::string& error) {
  std::ifstream in(file, std::ios::binary);
  if (!in) {
    error = file + ": cannot read";
    return false;
  }
  text.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  if (in.bad()) {
    error = file + ": cannot read";
    return false;
  }
  return parse_fit_options(text, file, options, error);
}

Failure fit_tile(const std::filesystem::path& path, const std::string& name,
                 const fit::FitPipelineOptions& options, const std::string& crs_override,
                 FittedTile& out) {
  const auto start = std::chrono::steady_clock::now();
  out = FittedTile{};
  // Every point is read (the pipeline needs the whole tile), in the local frame. Only
  // coordinates, returns and classes are used: layered LAZ skips its other layers.
  geo::PointReadOptions read_options;
  read_options.all_attributes = false;
  auto opened = geo::open_point_file(path, read_options);
  if (!opened.ok()) return {from_kernel(opened.error().code), opened.error().message};
  geo::PointReader& reader = *opened.value();
  std::array<double, 3> origin{0.0, 0.0, 0.0};
  std::string crs_text;
  const auto* las = dynamic_cast<const geo::LasReader*>(&reader);
  // The CRS as the run records it: "EPSG:h[+v]" for EPSG codes, else WKT 1.
  auto crs_label = [](const geo::Crs& v) {
    if (v.epsg == 0) return geo::crs_to_wkt1(v);
    std::string text = "EPSG:" + std::to_string(v.epsg);
    if (v.vertical && v.vertical->epsg != 0) text += "+" + std::to_string(v.vertical->epsg);
    return text;
  };
  std::optional<geo::Crs> given;
  if (!crs_override.empty()) {
    auto parsed = geo::crs_from_config(crs_override);
    if (!parsed.ok()) {
      return {ErrorCode::ConfigInvalid, "CRS " + crs_override + ": " + parsed.error().message};
    }
    given = std::move(parsed).value();
    crs_text = crs_label(*given);
  }
  if (las != nullptr) {
    origin = las->header().offset;
    auto own = geo::las_file_crs(las->crs(), "");
    if (given && own.ok()) {
      // The run's CRS is for tiles without one; a tile that says otherwise is an error.
      if (auto diff = geo::crs_difference(own.value(), *given)) {
        return {ErrorCode::InputInvalid,
                "the tile's CRS (" + geo::describe_crs(own.value()) + ") differs from run.crs (" +
                    crs_override + ": " + geo::describe_crs(*given) + "): " + *diff};
      }
    } else if (!given && own.ok()) {
      crs_text = crs_label(own.value());
    }
  }
  std::vector<kernel::Vec3> raw;
  std::vector<std::uint8_t> classes;
  const bool has_classes = reader.info().fields.classification;
  geo::PointBatch batch;
  for (;;) {
    auto n = reader.read(batch, 1 << 16);
    if (!n.ok()) return {from_kernel(n.error().code), n.error().message};
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
  out.read_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  auto fitted = fit::fit_point_cloud(raw, classes, options);
  if (!fitted.ok()) return {ErrorCode::ConfigInvalid, fitted.error().message};
  out.output = std::move(fitted).value();
  out.scene.name = name;
  out.scene.seed = options.ransac.seed;
  if (!crs_text.empty() || las != nullptr) out.scene.frame = geo::SceneFrame{crs_text, origin};
  out.scene.primitives = out.output.primitives;
  return {};
}

}  // namespace csgtile::worker::city
