// `csgtile fit INPUT [--config C.yaml] --out primitives.json [--json] [--seed N] [--crs EPSG:N]`:
// reads a LAS/LAZ/PLY/PCD/XYZ point cloud, segments it, fits primitives (csgtile/fit/*.h)
// and writes them in the scene format, in the tile-local frame (origin = the LAS offset near
// the points, else the floor of the smallest x and y) with the CRS and the seed. The file
// holds no timings: the same input, config and seed give the same bytes. Counts per type,
// unassigned points, rejections with reasons and per-stage timings go to stdout.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sstream>

#include "city/fit_tile.h"
#include "commands.h"
#include "csgtile/fit/segment.h"
#include "csgtile/geo/crs.h"
#include "csgtile/geo/las.h"
#include "csgtile/geo/point_reader.h"
#include "csgtile/geo/scene.h"
#include "csgtile/worker/errors.h"
#include "csgtile/worker/publish.h"
#include "fetch/fetch.h"
#include "fetch/input.h"
#include "little_endian.h"

namespace csgtile::worker::detail {

namespace {

using Json = nlohmann::ordered_json;

struct FitCommand {
  std::string input;
  std::string config;
  std::string out;
  std::string crs;
  std::string dump_shapes;
  std::string segments;
  std::string footprints, footprints_layer, footprints_id;
  std::uint64_t seed = 1;
  bool seed_given = false;
  bool json = false;
};

// The RANSAC's view of every region as text: "P region x y z nx ny nz shape" per point and
// "S region index type px py pz ax ay az inliers" per shape (tests/bench/beam_causes.py).
bool write_detections(const std::string& path, const std::vector<fit::RegionDetection>& regions) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (f == nullptr) return false;
  for (std::size_t r = 0; r < regions.size(); ++r) {
    const auto& d = regions[r];
    for (std::size_t i = 0; i < d.points.size(); ++i) {
      const auto& p = d.points[i];
      const auto& n = d.normals[i];
      std::fprintf(f, "P %zu %.4f %.4f %.4f %.3f %.3f %.3f %d\n", r, p.x(), p.y(), p.z(), n.x(),
                   n.y(), n.z(), i < d.shapes.assignment.size() ? d.shapes.assignment[i] : -1);
    }
    for (std::size_t s = 0; s < d.shapes.shapes.size(); ++s) {
      const fit::Surface& q = d.shapes.shapes[s].surface;
      std::fprintf(f, "S %zu %zu %d %.4f %.4f %.4f %.5f %.5f %.5f %zu\n", r, s,
                   static_cast<int>(q.type), q.point.x(), q.point.y(), q.point.z(), q.axis.x(),
                   q.axis.y(), q.axis.z(), d.shapes.shapes[s].inliers.size());
    }
  }
  return std::fclose(f) == 0;
}

Json vec_json(const kernel::Vec3& v) { return Json::array({v.x(), v.y(), v.z()}); }

// The segmentation: PREFIX.i32, one little-endian int32 per input point in input order (its
// surface's id, -1 for none), and PREFIX.json, the surfaces with their parameters in the
// scene's frame (tile-local: add `origin` for CRS coordinates).
Failure write_segments(const std::string& prefix, const fit::FitOutput& f,
                       const std::array<double, 3>& origin) {
  std::string bytes;
  bytes.reserve(f.point_segment.size() * 4);
  for (const std::int32_t s : f.point_segment) put_u32(bytes, static_cast<std::uint32_t>(s));
  std::vector<long long> points(f.segments.size(), 0);
  for (auto s : f.point_segment) {
    if (s >= 0) ++points[static_cast<std::size_t>(s)];
  }
  Json surfaces = Json::array();
  for (std::size_t i = 0; i < f.segments.size(); ++i) {
    const fit::Segment& seg = f.segments[i];
    const fit::Surface& q = seg.surface;
    Json j;
    j["id"] = static_cast<long long>(i);
    j["type"] = fit::shape_type_name(q.type);
    j["region"] = seg.region;
    switch (q.type) {
      case fit::ShapeType::Plane:
        j["point"] = vec_json(q.point);
        j["normal"] = vec_json(q.axis);
        break;
      case fit::ShapeType::Sphere:
        j["center"] = vec_json(q.point);
        j["radius"] = q.radius;
        break;
      case fit::ShapeType::Cylinder:
        j["point"] = vec_json(q.point);
        j["axis"] = vec_json(q.axis);
        j["radius"] = q.radius;
        break;
      case fit::ShapeType::Cone:
        j["apex"] = vec_json(q.point);
        j["axis"] = vec_json(q.axis);
        j["half_angle_deg"] = q.angle * 180.0 / std::numbers::pi;
        break;
      case fit::ShapeType::Torus:
        j["center"] = vec_json(q.point);
        j["axis"] = vec_json(q.axis);
        j["major_radius"] = q.radius;
        j["minor_radius"] = q.radius2;
        break;
    }
    j["inliers"] = seg.inliers;
    j["points"] = points[i];
    j["rms"] = seg.rms;
    surfaces.push_back(std::move(j));
  }
  Json doc;
  doc["points"] = static_cast<long long>(f.point_segment.size());
  doc["origin"] = Json::array({origin[0], origin[1], origin[2]});
  doc["surfaces"] = std::move(surfaces);
  if (Failure w = write_file_atomic(prefix + ".i32", bytes); !w.ok()) return w;
  return write_file_atomic(prefix + ".json", doc.dump(1) + "\n");
}

double since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

int run_fit(const FitCommand& c) {
  const auto start = std::chrono::steady_clock::now();
  Json out;
  out["input"] = c.input;
  auto fail = [&](const Failure& f) { return detail::report_failure("fit", f, c.json, out); };

  // The csgtile config (its fit: section, run.seed, run.crs, kernel.linear_tolerance), every
  // problem printed with its key and line; no --config: the defaults.
  config::Config config;
  if (!c.config.empty()) {
    auto loaded = load_run_config(c.config, RunChecks::CrsOnly);
    if (!loaded) return fail({ErrorCode::ConfigInvalid, c.config + ": invalid config"});
    config = std::move(*loaded);
  }
  if (c.seed_given) config.run.seed = c.seed;
  const std::string crs = c.crs.empty() ? config.run.crs : c.crs;
  fit::FitPipelineOptions options = city::fit_options(config);
  options.keep_detections = !c.dump_shapes.empty();
  options.keep_segments = !c.segments.empty();
  if (!c.crs.empty() && !geo::crs_from_config(c.crs).ok()) {
    return fail({ErrorCode::Usage, "--crs: " + geo::crs_from_config(c.crs).error().message});
  }
  city::FittedTile tile;
  city::TileSource source;
  source.path = c.input;
  if (fetch::is_remote_url(c.input)) {
    // A LAS/LAZ/COPC URL (http, https, s3): read by range requests under the config's policy.
    if (Failure f =
            fetch::open_range_source(c.input, fetch::policy_of(config.fetch), source.remote);
        !f.ok()) {
      return fail(f);
    }
  }
  const std::string stem =
      std::filesystem::path(c.input.substr(0, c.input.find_first_of("?#"))).stem().string();
  // Footprints: the flags, else the config's city.footprints*.
  const geo::FootprintSource footprints{
      c.footprints.empty() ? config.city.footprints : c.footprints,
      c.footprints.empty() ? config.city.footprints_layer : c.footprints_layer,
      c.footprints.empty() ? config.city.footprints_id : c.footprints_id};
  if (Failure f = city::fit_tile(std::move(source), stem, options, crs, tile, footprints);
      !f.ok()) {
    return fail(f);
  }
  const fit::FitOutput& f = tile.output;
  const double read_seconds = tile.read_seconds;
  const std::string text = geo::scene_to_json(tile.scene);
  if (Failure w = write_file_atomic(c.out, text); !w.ok()) return fail(w);

  if (!c.dump_shapes.empty() && !write_detections(c.dump_shapes, f.detections)) {
    return fail({ErrorCode::Io, c.dump_shapes + ": cannot write"});
  }
  if (!c.segments.empty()) {
    if (Failure w = write_segments(c.segments, f, tile.origin); !w.ok()) {
      return fail(w);
    }
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
  out.update(city::fit_counts_json(f));
  if (!footprints.source.empty()) out["footprints"] = city::footprints_record(footprints, tile);
  out["cluster_tolerance"] = f.cluster_tolerance;
  Json regions = Json::array();
  for (const auto& r : f.region_stats) {
    regions.push_back(Json{{"points", r.points},
                           {"spacing", r.spacing},
                           {"cluster_epsilon", r.cluster_epsilon},
                           {"epsilon", r.epsilon},
                           {"min_points", r.min_points},
                           {"shapes", r.shapes},
                           {"primitives", r.primitives},
                           {"candidates", r.candidates},
                           {"building", r.building}});
  }
  out["region_stats"] = regions;
  out["candidates"] = f.candidates;
  out["primitives"] = static_cast<long long>(f.primitives.size());
  if (!c.segments.empty()) {
    out["surfaces"] = static_cast<long long>(f.segments.size());
    out["segments"] = c.segments;
  }
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
  std::printf("%-20s%lld (ground %lld, other classes %lld, outliers %lld)\n", "points",
              f.input_points, f.ground_points, f.other_class_points, f.outlier_points);
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
                  "csgtile config (YAML, with CSGTILE_* overrides): its fit: section, run.seed, "
                  "run.crs and kernel.linear_tolerance");
  cmd->add_option("--seed", c->seed, "Seed of the RANSAC (replaces the config's run.seed)");
  cmd->add_option("--crs", c->crs,
                  "CRS to assume when the file has none (EPSG:code[+vertical]; replaces the "
                  "config's run.crs)");
  cmd->add_flag("--json", c->json, "Print one JSON object");
  cmd->add_option("--footprints", c->footprints,
                  "Building footprints: any vector source GDAL reads (path, URL, PG:...); one "
                  "building per footprint (replaces the config's city.footprints)");
  cmd->add_option("--footprints-layer", c->footprints_layer, "Its layer (default: the only one)");
  cmd->add_option("--footprints-id", c->footprints_id,
                  "Its attribute carried to the outputs as the building's id (default: the "
                  "feature id)");
  cmd->add_option("--dump-shapes", c->dump_shapes,
                  "Diagnostics: write every region's points, normals and RANSAC shapes to this "
                  "text file (tests/bench/beam_causes.py reads it)");
  cmd->add_option("--segments", c->segments,
                  "Write the segmentation: PREFIX.i32 (one little-endian int32 per input point, "
                  "in input order: its detected surface's id, -1 for none) and PREFIX.json "
                  "(per surface: id, type, parameters, inliers, RMS)");
  cmd->callback([&action, c, cmd] {
    c->seed_given = cmd->count("--seed") > 0;
    action = [c] { return run_fit(*c); };
  });
}

}  // namespace csgtile::worker::detail
