// The `fit` job of a city run: one LIDAR tile → its fitted primitives, published as a scene
// file in the tile's frame, with the cells holding their anchors (city_jobs.h).

#include <map>
#include <set>

#include "city/city_internal.h"
#include "city/fit_tile.h"
#include "csgtile/geo/scene.h"
#include "csgtile/kernel/check.h"
#include "csgtile/kernel/mass_properties.h"
#include "csgtile/kernel/primitives.h"
#include "csgtile/worker/publish.h"
#include "fetch/input.h"
#include "ops/metrics.h"
#include "ops/stage_clock.h"

namespace csgtile::worker::city::detail {

Failure run_fit_job(const Job& job, const std::filesystem::path& run_dir,
                    const config::Config& config, std::string& result, StageTimings* timings) {
  ops::StageClock clock(timings);
  clock.enter("fetch");
  std::string input;
  fetch::LocalInput local;
  if (Failure f = fetch::resolve_job_input(job, config, input, local); !f.ok()) return f;
  const auto payload = nlohmann::json::parse(job.payload);  // valid: resolve_job_input read it

  clock.enter("fit");
  const fit::FitPipelineOptions options = fit_options(config);
  FittedTile tile;
  const std::string name = std::filesystem::path(local.path).stem().string();
  if (Failure f = fit_tile(local.path, name, options, config.run.crs, tile); !f.ok()) {
    // Name the input once: readers already name the file they read (for a URL, its local
    // copy, which the input's name then replaces).
    const std::string local_name = std::filesystem::path(local.path).string();
    const std::size_t at = f.message.find(local_name);
    if (at == std::string::npos) {
      f.message = input + ": " + f.message;
    } else if (input != local_name) {
      f.message.replace(at, local_name.size(), input);
    }
    return f;
  }
  const fit::FitOutput& fit = tile.output;
  ops::metrics().add_points_processed(static_cast<std::uint64_t>(fit.input_points));

  // Each primitive is built as a kernel solid and checked; its box (in CRS coordinates, the
  // tile origin added) gives its anchor cell. A primitive that is not a valid solid is left
  // out with its reason.
  clock.enter("check");
  const std::array<double, 3> origin =
      tile.scene.frame ? tile.scene.frame->origin : std::array<double, 3>{0, 0, 0};
  const kernel::Vec3 o(origin[0], origin[1], origin[2]);
  std::vector<geo::ScenePrimitive> kept;
  ordered_json invalid = ordered_json::array();
  for (const geo::ScenePrimitive& p : tile.scene.primitives) {
    auto solid = kernel::build_primitive(p.spec, config.kernel.linear_tolerance);
    std::string reason;
    if (!solid.ok()) {
      reason = solid.error().message;
    } else if (const kernel::CheckReport check = kernel::check_shape(solid.value()); !check.valid()) {
      reason = std::string(kernel::check_status_name(check.issues.front().status)) + ": " +
               check.issues.front().message;
    }
    if (!reason.empty()) {
      invalid.push_back({{"id", p.id}, {"reason", reason}});
      continue;
    }
    kept.push_back(p);
  }
  ops::metrics().add_primitives_built(kept.size());
  tile.scene.primitives = std::move(kept);

  clock.enter("publish");
  const std::string text = geo::scene_to_json(tile.scene);
  // Anchors from the file as the assemble jobs will read it (primitive_crs_box): the same
  // bytes through the same code, so every job puts a primitive in the same cell.
  auto published = geo::parse_scene(text);
  if (!published.ok()) return {ErrorCode::Internal, input + ": " + published.error().message};
  kernel::BoundingBox bounds;
  std::map<std::string, Cell> anchors;
  for (const geo::ScenePrimitive& p : published->primitives) {
    const kernel::BoundingBox box = primitive_crs_box(p.spec, o, config.kernel.linear_tolerance);
    if (box.empty()) return {ErrorCode::Internal, input + ": primitive " + p.id + " does not rebuild"};
    bounds.add(box);
    const Cell cell = cell_of(box.min.x(), box.min.y(), config.city.cell_size);
    anchors.emplace(cell.name(), cell);
  }
  const std::string sha = sha256_hex(text);
  const std::string key = "fits/" + sha + ".json";
  if (Failure f = publish_object(run_dir, key, text); !f.ok()) return f;

  ordered_json record;
  record["input"] = input;
  record["input_sha256"] = local.sha256;
  record["tile"] = payload.value("tile", 0);
  record["scene"] = {{"key", key}, {"sha256", sha}, {"bytes", text.size()}};
  record["crs"] = tile.scene.frame ? tile.scene.frame->crs : std::string();
  record["origin"] = origin;
  record["seed"] = options.ransac.seed;
  // The fit section as the canonical config JSON writes it: same options, same hash.
  record["fit_options_sha256"] = sha256_hex(config::to_json(config.fit));
  record["points"] = fit.input_points;
  record["ground_points"] = fit.ground_points;
  record["other_class_points"] = fit.other_class_points;
  record["outlier_points"] = fit.outlier_points;
  record["fitted_points"] = fit.fitted_points;
  record["assigned_points"] = fit.assigned_points;
  record["unassigned_points"] = fit.unassigned_points;
  record["regions"] = fit.regions;
  record["primitives"] = tile.scene.primitives.size();
  ordered_json per_type = ordered_json::object();
  for (const geo::ScenePrimitive& p : tile.scene.primitives) {
    per_type[kernel::primitive_type_name(p.spec.type)] =
        per_type.value(kernel::primitive_type_name(p.spec.type), 0) + 1;
  }
  record["per_type"] = per_type;
  std::map<std::string, long long> reasons;
  for (const auto& r : fit.rejected) reasons[r.reason] += 1;
  record["rejected"] = reasons;
  record["invalid_primitives"] = invalid;
  record["bounds"] = bounds.empty() ? ordered_json()
                                    : ordered_json::array({bounds.min.x(), bounds.min.y(),
                                                           bounds.min.z(), bounds.max.x(),
                                                           bounds.max.y(), bounds.max.z()});
  ordered_json cells = ordered_json::array();
  for (const auto& [cell_name, cell] : anchors) {
    cells.push_back({{"name", cell_name}, {"column", cell.column}, {"row", cell.row}});
  }
  record["anchor_cells"] = cells;
  result = record.dump();
  return {};
}

}  // namespace csgtile::worker::city::detail
