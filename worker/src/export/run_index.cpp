// The run's topology index from its published models (see run_index.h).

#include "export/run_index.h"

#include <algorithm>
#include <chrono>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>

#include "csgtile/geo/crs.h"
#include "csgtile/kernel/explorer.h"
#include "csgtile/kernel/native_format.h"
#include "csgtile/worker/files.h"
#include "csgtile/worker/publish.h"

namespace csgtile::worker {

namespace {

using kernel::ShapeKind;

// Scene primitives by the label their CSG leaf carries (the run labels leaves with the
// primitive's id, or "p<index>" when it has none).
std::map<std::string, const geo::ScenePrimitive*> primitives_by_label(const geo::Scene* scene) {
  std::map<std::string, const geo::ScenePrimitive*> out;
  if (scene == nullptr) return out;
  for (std::size_t i = 0; i < scene->primitives.size(); ++i) {
    const auto& p = scene->primitives[i];
    out.emplace(p.id.empty() ? "p" + std::to_string(i) : p.id, &p);
  }
  return out;
}

PrimitiveInfo scene_primitive_info(int node, const kernel::CsgNode& leaf,
                                   const std::map<std::string, const geo::ScenePrimitive*>& scene) {
  const auto it = scene.find(leaf.label);
  return primitive_info(node, leaf, it == scene.end() ? std::nullopt : it->second->quality);
}

}  // namespace

PrimitiveInfo primitive_info(int node, const kernel::CsgNode& leaf,
                             const std::optional<geo::FitQuality>& quality) {
  PrimitiveInfo info;
  info.node = node;
  info.id = leaf.label;
  info.type = kernel::primitive_type_name(leaf.primitive.type);
  if (quality) {
    info.inliers = quality->inliers;
    info.rms = quality->rms;
    info.coverage = quality->coverage;
    info.within_2sigma = quality->within_2sigma;
  }
  return info;
}

std::vector<PrimitiveInfo> model_primitives(
    const kernel::CsgModel& model,
    const std::function<std::optional<geo::FitQuality>(const std::string&)>& quality) {
  std::vector<PrimitiveInfo> out;
  for (std::size_t n = 0; n < model.nodes.size(); ++n) {
    const kernel::CsgNode& node = model.nodes[n];
    if (node.kind != kernel::CsgNodeKind::Primitive) continue;
    out.push_back(primitive_info(static_cast<int>(n), node, quality(node.label)));
  }
  return out;
}

std::vector<IndexObject> job_index_objects(std::size_t input_index, const kernel::CsgModel& model,
                                           const geo::Scene* scene) {
  std::vector<IndexObject> out;
  if (model.shape.is_null()) return out;
  const auto labels = primitives_by_label(scene);
  const kernel::ShapeIndex solids = kernel::map_child_shapes(model.shape, ShapeKind::Solid);
  const kernel::ShapeIndex model_faces = kernel::map_child_shapes(model.shape, ShapeKind::Face);
  // A set of primitives is published without history; its i-th solid is the i-th primitive
  // as built (same faces in the same order), so its leaf history is exact.
  const bool set_of_primitives = model.nodes.empty() && scene != nullptr &&
                                 scene->op == geo::BooleanOp::None &&
                                 solids.size() == scene->primitives.size();
  for (std::size_t s = 0; s < solids.size(); ++s) {
    IndexObject object;
    object.id = std::to_string(input_index) + "-" + std::to_string(s);
    object.model.shape = solids[s];
    const kernel::ShapeIndex faces = kernel::map_child_shapes(solids[s], ShapeKind::Face);
    if (set_of_primitives) {
      const geo::ScenePrimitive& p = scene->primitives[s];
      kernel::CsgNode leaf;
      leaf.kind = kernel::CsgNodeKind::Primitive;
      leaf.primitive = p.spec;
      leaf.label = p.id.empty() ? "p" + std::to_string(s) : p.id;
      object.model.nodes.push_back(leaf);
      for (std::size_t f = 0; f < faces.size(); ++f) {
        object.model.face_sources.push_back({kernel::FaceSource{0, static_cast<int>(f)}});
      }
      object.primitives.push_back(scene_primitive_info(0, leaf, labels));
    } else if (!model.nodes.empty() && model.face_sources.size() == model_faces.size()) {
      object.model.nodes = model.nodes;
      std::set<int> contributing;
      for (std::size_t f = 0; f < faces.size(); ++f) {
        const std::size_t m = model_faces.find(faces[f]);
        object.model.face_sources.push_back(m == kernel::ShapeIndex::npos
                                                ? std::vector<kernel::FaceSource>{}
                                                : model.face_sources[m]);
        for (const kernel::FaceSource& src : object.model.face_sources.back())
          contributing.insert(src.node);
      }
      for (std::size_t n = 0; n < model.nodes.size(); ++n) {
        if (model.nodes[n].kind != kernel::CsgNodeKind::Primitive) continue;
        if (solids.size() > 1 && !contributing.count(static_cast<int>(n))) continue;
        object.primitives.push_back(
            scene_primitive_info(static_cast<int>(n), model.nodes[n], labels));
      }
    }
    out.push_back(std::move(object));
  }
  return out;
}

Failure collect_run_objects(const RunJobs& run_jobs, const RunExportOptions& options,
                            const std::vector<std::pair<std::string, std::string>>& results,
                            const std::filesystem::path& run_dir, RunObjects& out) {
  out = RunObjects{};
  std::map<std::string, std::string> by_key(results.begin(), results.end());
  struct Job {
    std::size_t input_index;
    kernel::CsgModel model;
    std::optional<geo::Scene> scene;
  };
  std::vector<Job> jobs;
  std::set<std::string> seen;
  for (std::size_t i = 0; i < run_jobs.inputs.size(); ++i) {
    const std::string& input = run_jobs.inputs[i];
    if (!seen.insert(input).second) continue;  // one job per distinct input
    const auto it = by_key.find("build:" + run_jobs.run + ":" + input);
    if (it == by_key.end()) continue;  // dead or not run: reported in the manifest
    const auto record = nlohmann::json::parse(it->second, nullptr, false);
    if (record.is_discarded() || !record.contains("model") || !record["model"].contains("key") ||
        !record["model"]["key"].is_string()) {
      return {ErrorCode::Internal, "job " + it->first + " has a malformed result record"};
    }
    const std::string key = record["model"]["key"].get<std::string>();
    if (!is_safe_key(key)) return {ErrorCode::Internal, "unsafe model key " + key};
    auto model = kernel::read_native_model_file(run_dir / key);
    if (!model.ok()) {
      return failure_of(model.error(), (run_dir / key).string());
    }
    Job job{i, std::move(model).value(), std::nullopt};
    // The scene gives fit quality and the frame; an input that went away since its job ran
    // still has its model indexed.
    if (auto scene = geo::read_scene(input); scene.ok()) job.scene = std::move(scene).value();
    jobs.push_back(std::move(job));
  }

  // One frame for all objects: the first job's origin in the common CRS.
  bool common_crs = !jobs.empty();
  for (const Job& job : jobs) {
    common_crs &=
        job.scene && job.scene->frame && job.scene->frame->crs == jobs[0].scene->frame->crs;
  }
  const bool any_frame =
      std::any_of(jobs.begin(), jobs.end(), [](const Job& j) { return j.scene && j.scene->frame; });
  if (common_crs) {
    auto crs = geo::crs_from_config(jobs[0].scene->frame->crs);
    if (crs.ok() && crs->epsg > 0) {
      out.crs = std::move(crs).value();
      const auto& o = jobs[0].scene->frame->origin;
      out.origin = kernel::Vec3(o[0], o[1], o[2]);
    } else {
      common_crs = false;
    }
  }
  if (any_frame && !common_crs) {
    out.warnings.push_back(
        "the inputs do not share one EPSG CRS: the exports use each scene's local coordinates "
        "without a CRS");
  }

  for (const Job& job : jobs) {
    std::vector<IndexObject> mine =
        job_index_objects(job.input_index, job.model, job.scene ? &*job.scene : nullptr);
    if (common_crs) {
      const auto& o = job.scene->frame->origin;
      const kernel::Vec3 offset = kernel::Vec3(o[0], o[1], o[2]) - out.origin;
      if (!offset.isZero(0.0)) {
        for (IndexObject& object : mine) {
          move_model(object.model, kernel::Location::translation(offset));
        }
      }
    }
    for (IndexObject& object : mine) out.objects.push_back(std::move(object));
  }
  add_building_lods(out.objects, options.chordal_tolerance, options.linear_tolerance);
  return {};
}

Failure write_run_index(const RunExportOptions& settings, const RunObjects& run,
                        const std::filesystem::path& run_dir, RunIndexReport& report) {
  const auto start = std::chrono::steady_clock::now();
  IndexOptions options;
  options.chordal_tolerance = settings.chordal_tolerance;
  options.linear_tolerance = settings.linear_tolerance;
  options.threads = settings.threads;
  options.cell_relations = run.cell_relations;
  if (run.crs) {
    geo::Crs horizontal = *run.crs;
    horizontal.vertical.reset();  // srs_id names the horizontal EPSG code
    options.srs.srs_id = horizontal.epsg;
    options.srs.organization = "EPSG";
    options.srs.organization_coordsys_id = horizontal.epsg;
    options.srs.name = horizontal.name;
    options.srs.definition_wkt = geo::crs_to_horizontal_wkt1(horizontal);
    const kernel::Vec3 origin = run.origin;
    options.to_srs = [origin](const kernel::Vec3& p) { return kernel::Vec3(p + origin); };
  }

  const std::filesystem::path path = run_dir / report.key;
  if (run.cell_indexes.empty()) {
    if (Failure f = write_topology_index(path, run.objects, options, &report.stats); !f.ok()) {
      return {f.code, path.string() + ": " + f.message};
    }
  } else {
    if (Failure f =
            merge_topology_indexes(path, run.cell_indexes, run.objects, options, &report.stats);
        !f.ok()) {
      return {f.code, path.string() + ": " + f.message};
    }
    report.stats.warnings = run.cell_index_warnings;
  }
  for (const std::string& w : run.warnings) report.stats.warnings.push_back(w);
  std::uint64_t bytes = 0;
  if (Failure f = file_sha256(path, report.sha256, bytes); !f.ok()) {
    return {ErrorCode::Io, "cannot read back " + path.string()};
  }
  report.bytes = bytes;
  report.srs_id = options.srs.srs_id;
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return {};
}

}  // namespace csgtile::worker
