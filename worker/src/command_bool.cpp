// `csgtile bool CASE.json [--json] [--out MODEL.csgt]`: builds a scene's primitives, applies
// its operation, reports the spec's result fields (../shared/spec/scene-format.md) and, with
// --out, writes the native model with its CSG tree and face history.

#include <chrono>
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>

#include "commands.h"
#include "csgtile/geo/scene.h"
#include "csgtile/geo/scene_model.h"
#include "csgtile/kernel/boolean.h"
#include "csgtile/kernel/check.h"
#include "csgtile/kernel/csg.h"
#include "csgtile/kernel/explorer.h"
#include "csgtile/kernel/mass_properties.h"
#include "csgtile/kernel/native_format.h"
#include "csgtile/worker/errors.h"
#include "snap_json.h"

namespace csgtile::worker::detail {

namespace {

struct BoolReport {
  std::string name, op;
  bool valid = false;
  double volume = 0, area = 0, seconds = 0;
  std::array<std::size_t, kernel::kShapeKindCount> counts{};
  std::string error;
  std::vector<std::string> issues;
  std::optional<kernel::SnapReport> snap;
};

// Runs the scene; the failure code is Ok when the scene was evaluated (valid or not).
Failure evaluate(const std::string& path, const std::string& out, const kernel::SnapOptions& snap,
                 double tolerance, BoolReport& report) {
  const auto start = std::chrono::steady_clock::now();
  auto scene = geo::read_scene(path);
  if (!scene.ok()) {
    return {
        scene.error().code == kernel::ErrorCode::IoError ? ErrorCode::Io : ErrorCode::InputInvalid,
        scene.error().message};
  }
  report.name = scene->name;
  report.op = geo::boolean_op_name(scene->op);
  geo::Scene built = std::move(scene).value();
  if (snap.distance > 0.0 || snap.angle > 0.0) {
    std::vector<kernel::PrimitiveSpec> specs;
    for (const auto& p : built.primitives) specs.push_back(p.spec);
    kernel::SnapReport snapped;
    auto moved = kernel::snap_primitives(specs, snap, &snapped);
    if (!moved.ok()) return {ErrorCode::InputInvalid, moved.error().message};
    for (std::size_t i = 0; i < specs.size(); ++i) built.primitives[i].spec = moved.value()[i];
    report.snap = snapped;
  }
  // The scene build job's path (geo/scene_model.h), at kernel.linear_tolerance.
  geo::SceneModelOptions options;
  options.tolerance = tolerance;
  auto leaves = geo::scene_leaves(built, options);
  if (!leaves.ok()) return failure_of(leaves.error());
  kernel::Result<kernel::CsgModel> model = geo::combine_scene(built.op, leaves.value(), options);
  if (!model.ok()) return failure_of(model.error());
  if (!out.empty()) {
    if (auto st = kernel::write_native_model_file(out, model.value()); !st.ok()) {
      return {ErrorCode::Io, st.error().message};
    }
  }
  const kernel::Result<kernel::Shape> compound = model.value().shape;
  const kernel::CheckReport check = kernel::check_shape(compound.value());
  const kernel::MassProperties mp = kernel::mass_properties(compound.value());
  report.counts = kernel::count_shapes(compound.value());
  report.valid = check.valid();
  for (const auto& issue : check.issues) {
    report.issues.push_back(std::string(kernel::check_status_name(issue.status)) + ": " +
                            issue.message);
  }
  report.volume = mp.volume;
  report.area = mp.area;
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return {};
}

}  // namespace

void register_bool(CLI::App& app, Action& action) {
  auto* cmd = app.add_subcommand(
      "bool",
      "Build a scene's primitives (scene format of shared/spec) and report validity, "
      "volume, area and topology counts");
  auto file = std::make_shared<std::string>();
  auto json = std::make_shared<bool>(false);
  auto model_path = std::make_shared<std::string>();
  cmd->add_option("CASE", *file, "Scene / case JSON file")->required();
  cmd->add_option("--out", *model_path,
                  "Write the result as a native model (.csgt) with its CSG tree and face history");
  cmd->add_flag("--json", *json, "Print one JSON object with the spec's result fields");
  auto config_path = std::make_shared<std::string>();
  cmd->add_option("--config", *config_path,
                  "csgtile config: its kernel.linear_tolerance builds the primitives and runs "
                  "the Booleans (default: the config defaults)");
  auto snap = std::make_shared<kernel::SnapOptions>();
  auto snap_degrees = std::make_shared<double>(0.0);
  cmd->add_option("--snap-distance", snap->distance,
                  "Fuzzy mode for fitted primitives: plane faces whose planes lie this close "
                  "(world units) become one plane before the operation (kernel/snap.h)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--snap-angle", *snap_degrees,
                  "Fuzzy mode: primitive axes within this angle (degrees) become one direction")
      ->check(CLI::Range(0.0, 45.0));
  cmd->callback([&action, file, json, model_path, snap, snap_degrees, config_path] {
    *snap = snap_options(snap->distance, *snap_degrees);
    action = [file, json, model_path, snap, config_path] {
      config::Config config;
      if (!config_path->empty()) {
        auto loaded = load_run_config(*config_path, RunChecks::CrsOnly);
        if (!loaded) return error_info(ErrorCode::ConfigInvalid).exit_code;
        config = std::move(*loaded);
      }
      BoolReport r;
      const Failure failure =
          evaluate(*file, *model_path, *snap, config.kernel.linear_tolerance, r);
      auto count = [&](kernel::ShapeKind k) { return r.counts[static_cast<int>(k)]; };
      if (*json) {
        nlohmann::ordered_json out;
        out["name"] = r.name;
        out["op"] = r.op.empty() ? nlohmann::ordered_json() : nlohmann::ordered_json(r.op);
        out["valid"] = failure.ok() && r.valid;
        out["volume"] = r.volume;
        out["area"] = r.area;
        out["topology"] = {{"solids", count(kernel::ShapeKind::Solid)},
                           {"shells", count(kernel::ShapeKind::Shell)},
                           {"faces", count(kernel::ShapeKind::Face)},
                           {"edges", count(kernel::ShapeKind::Edge)},
                           {"vertices", count(kernel::ShapeKind::Vertex)}};
        out["seconds"] = r.seconds;
        if (r.snap) out["snap"] = snap_report_json(*r.snap);
        if (!failure.ok()) {
          out["error"] = std::string(error_info(failure.code).name) + ": " + failure.message;
        } else if (!r.valid) {
          out["error"] = "invalid result: " + (r.issues.empty() ? std::string() : r.issues.front());
        } else {
          out["error"] = nullptr;
        }
        std::cout << out.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace) << "\n";
      } else if (failure.ok()) {
        std::printf(
            "%s: %s  volume %.12g  area %.12g  solids %zu shells %zu faces %zu edges %zu "
            "vertices %zu  (%.4f s)\n",
            r.name.c_str(), r.valid ? "valid" : "INVALID", r.volume, r.area,
            count(kernel::ShapeKind::Solid), count(kernel::ShapeKind::Shell),
            count(kernel::ShapeKind::Face), count(kernel::ShapeKind::Edge),
            count(kernel::ShapeKind::Vertex), r.seconds);
        for (const auto& issue : r.issues) std::printf("  %s\n", issue.c_str());
      }
      if (!failure.ok()) {
        if (!*json) std::fprintf(stderr, "csgtile bool: %s\n", failure.message.c_str());
        return error_info(failure.code).exit_code;
      }
      return r.valid ? 0 : error_info(ErrorCode::ResultInvalid).exit_code;
    };
  });
}

}  // namespace csgtile::worker::detail
