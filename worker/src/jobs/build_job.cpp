// The scene build job (build_job.h).

#include "jobs/build_job.h"

#include <filesystem>
#include <nlohmann/json.hpp>

#include "csgtile/geo/scene.h"
#include "csgtile/geo/scene_model.h"
#include "csgtile/kernel/boolean.h"
#include "csgtile/kernel/check.h"
#include "csgtile/kernel/csg.h"
#include "csgtile/kernel/explorer.h"
#include "csgtile/kernel/mass_properties.h"
#include "csgtile/kernel/native_format.h"
#include "csgtile/worker/publish.h"
#include "fetch/fetch.h"
#include "fetch/input.h"
#include "ops/metrics.h"
#include "ops/stage_clock.h"

namespace csgtile::worker::jobs {

namespace {
using nlohmann::ordered_json;

ordered_json topology_json(const kernel::Shape& s) {
  const auto c = kernel::count_shapes(s);
  auto n = [&](kernel::ShapeKind k) { return c[static_cast<int>(k)]; };
  return {{"solids", n(kernel::ShapeKind::Solid)},
          {"shells", n(kernel::ShapeKind::Shell)},
          {"faces", n(kernel::ShapeKind::Face)},
          {"edges", n(kernel::ShapeKind::Edge)},
          {"vertices", n(kernel::ShapeKind::Vertex)}};
}
}  // namespace

Failure run_build_job(const Job& job, const JobContext& context, std::string& result,
                      StageTimings* timings) {
  const std::filesystem::path& run_dir = context.run_dir;
  const config::Config& config = context.config;
  const std::stop_token stop = context.stop;
  ops::StageClock clock(timings);
  clock.enter("fetch");
  std::string input;
  fetch::LocalInput local;
  if (Failure f = fetch::resolve_job_input(job, config, input, local); !f.ok()) return f;
  clock.enter("read");
  auto scene = geo::read_scene(local.path.string());
  if (!scene.ok()) {
    const std::string where =
        local.fetched ? input + " (fetched to " + local.path.string() + "): " : "";
    return {
        scene.error().code == kernel::ErrorCode::IoError ? ErrorCode::Io : ErrorCode::InputInvalid,
        where + scene.error().message};
  }
  ordered_json record;
  record["input"] = input;
  record["input_sha256"] = local.sha256;
  record["scene"] = scene->name;
  record["op"] = geo::boolean_op_name(scene->op);
  ordered_json objects = ordered_json::array();
  // The one path from a scene to a CSG model (geo/scene_model.h), at the configured tolerance.
  geo::SceneModelOptions scene_options;
  scene_options.tolerance = config.kernel.linear_tolerance;
  scene_options.interrupt.stop = stop;
  clock.enter("build");
  auto built = geo::scene_leaves(scene.value(), scene_options);
  if (!built.ok()) {
    return failure_of(built.error(), input);
  }
  std::vector<kernel::CsgModel>& leaves = built.value();
  clock.enter("check");
  for (std::size_t i = 0; i < leaves.size(); ++i) {
    const auto& p = scene->primitives[i];
    const kernel::Shape& solid = leaves[i].shape;
    const kernel::CheckReport check = kernel::check_shape(solid);
    if (!check.valid()) {
      return {ErrorCode::GeometryInvalid,
              input + ": primitives[" + std::to_string(i) + "] (" +
                  kernel::primitive_type_name(p.spec.type) +
                  "): " + kernel::check_status_name(check.issues.front().status) + ": " +
                  check.issues.front().message};
    }
    const kernel::MassProperties mp = kernel::mass_properties(solid);
    ordered_json o;
    o["id"] = p.id.empty() ? "p" + std::to_string(i) : p.id;
    o["type"] = kernel::primitive_type_name(p.spec.type);
    o["volume"] = mp.volume;
    o["area"] = mp.area;
    o["bounds"] = {mp.bounds.min.x(), mp.bounds.min.y(), mp.bounds.min.z(),
                   mp.bounds.max.x(), mp.bounds.max.y(), mp.bounds.max.z()};
    objects.push_back(std::move(o));
  }
  ops::metrics().add_primitives_built(leaves.size());
  clock.enter(scene->op == geo::BooleanOp::None ? "build" : "boolean");
  // A scene with an operation is unified by the exact Booleans (its CSG tree and face history
  // kept: native CSG section); a plain set stays a set.
  kernel::Result<kernel::CsgModel> model = geo::combine_scene(scene->op, leaves, scene_options);
  if (!model.ok()) return failure_of(model.error(), input);
  clock.enter("publish");
  // Content-addressed: the same model always lands under the same key, so a job that runs
  // twice (after a crash) rewrites identical bytes and publishes nothing new.
  const std::string bytes = kernel::write_native_model(model.value());
  const std::string sha = sha256_hex(bytes);
  const std::string key = "objects/" + sha + ".csgt";
  if (!is_safe_key(key)) return {ErrorCode::Internal, "unsafe object key " + key};
  if (!std::filesystem::exists(run_dir / key)) {
    if (Failure f = write_file_atomic(run_dir / key, bytes); !f.ok()) return f;
  }
  const kernel::MassProperties total = kernel::mass_properties(model.value().shape);
  record["primitives"] = objects;
  record["model"] = {{"key", key}, {"sha256", sha}, {"bytes", bytes.size()}};
  record["volume"] = total.volume;
  record["area"] = total.area;
  record["topology"] = topology_json(model.value().shape);
  record["csg_nodes"] = model.value().nodes.size();
  record["valid"] = true;
  result = record.dump();
  return {};
}

}  // namespace csgtile::worker::jobs
