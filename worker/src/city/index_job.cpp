// The `index` job of a city run: every cell's objects → the run's topology index, the root
// tileset naming the cells' tilesets, and the run manifest, written last (city_jobs.h).

#include <algorithm>
#include <map>
#include <set>

#include "city/block_records.h"
#include "city/city_internal.h"
#include "city/model_fit.h"
#include "city/relation_records.h"
#include "csgtile/geo/crs.h"
#include "csgtile/kernel/curve.h"
#include "csgtile/kernel/explorer.h"
#include "csgtile/kernel/location.h"
#include "csgtile/kernel/native_format.h"
#include "csgtile/kernel/surface.h"
#include "csgtile/kernel/tessellation.h"
#include "csgtile/worker/files.h"
#include "csgtile/worker/publish.h"
#include "export/manifest.h"
#include "export/report.h"
#include "export/run_index.h"
#include "export_settings.h"
#include "job_records.h"
#include "ops/memory.h"
#include "ops/stage_clock.h"
#include "publish/publish_run.h"
#include "snap_json.h"

namespace csgtile::worker::city::detail {

namespace {

/// The root tileset: one child per cell with tiles, each the cell's tileset as an external
/// tileset, the root region the union of theirs (cities do not cross the antimeridian).
Failure root_tileset(const std::filesystem::path& run_dir,
                     const std::vector<std::pair<std::string, ordered_json>>& cells,
                     std::string& text, std::size_t& children) {
  ordered_json kids = ordered_json::array();
  std::array<double, 6> region{INFINITY, INFINITY, -INFINITY, -INFINITY, INFINITY, -INFINITY};
  double error = 0.0;
  children = 0;
  for (const auto& [key, record] : cells) {
    if (!record.contains("tiles") || !record["tiles"].is_string()) continue;
    const std::string tiles = record["tiles"].get<std::string>();
    std::string body;
    if (Failure f = read_file_bytes(run_dir / tiles, body); !f.ok()) return f;
    const ordered_json cell = ordered_json::parse(body, nullptr, false);
    if (!cell.is_object() || !cell.contains("root")) {
      return {ErrorCode::Internal, tiles + ": not a tileset"};
    }
    const ordered_json& r = cell.at("root").at("boundingVolume").at("region");
    for (int i : {0, 1, 4}) region[i] = std::min(region[i], r[i].get<double>());
    for (int i : {2, 3, 5}) region[i] = std::max(region[i], r[i].get<double>());
    const double e = cell.at("geometricError").get<double>();
    error = std::max(error, e);
    kids.push_back({{"boundingVolume", {{"region", r}}},
                    {"geometricError", e},
                    {"content", {{"uri", "../" + tiles}}}});
    ++children;
  }
  if (children == 0) return {};
  ordered_json root;
  root["boundingVolume"] = {{"region", region}};
  root["geometricError"] = error;
  root["refine"] = "ADD";
  root["children"] = std::move(kids);
  ordered_json tileset;
  tileset["asset"] = {{"version", "1.1"}};
  tileset["geometricError"] = error;
  tileset["root"] = std::move(root);
  text = tileset.dump(2, ' ', false, ordered_json::error_handler_t::replace) + "\n";
  return {};
}

// A building's row of the report; nullopt for other objects. Heights in the CRS: the run
// frame's origin added.
std::optional<ReportBuilding> report_building(const IndexObject& object, double origin_z) {
  if (!is_building(object)) return std::nullopt;
  ReportBuilding b;
  b.lod = lod_reached(object);
  const FitSummary fit = fit_summary(object.primitives);
  b.fit_rms = fit.rms;
  b.fit_within_2sigma = fit.within_2sigma;
  if (const auto& m = object.model_fit) {
    b.model_rmse = m->rmse;
    b.model_within_2sigma = m->within_2sigma;
  }
  if (const auto& h = object.heights) {
    b.h_ground = h->ground + origin_z;
    b.h_roof_70p = h->roof_70p + origin_z;
    b.roof_surfaces = static_cast<long long>(h->roof_faces);
  }
  b.footprint_id = object.footprint_id;
  b.problem = building_problem(object);
  return b;
}

/// The convex hull (counter-clockwise) of the xy of `shape`: the footprint the report draws.
/// A shape of planar faces and straight edges is the hull of its vertices; any other, of its
/// tessellation's points at `chordal`. Empty when the shape cannot be tessellated.
std::vector<std::array<double, 2>> footprint_hull(const kernel::Shape& shape, double chordal) {
  std::vector<std::array<double, 2>> p;
  bool straight = true;
  for (const kernel::Shape& e : kernel::Explorer(shape, kernel::ShapeKind::Edge)) {
    const kernel::EdgeData* edge = e.body().edge();
    if (edge == nullptr || edge->degenerate()) continue;
    if (!edge->curve || edge->curve->kind() != kernel::CurveKind::Line) {
      straight = false;
      break;
    }
  }
  for (const kernel::Shape& f : kernel::Explorer(shape, kernel::ShapeKind::Face)) {
    if (!straight) break;
    const kernel::FaceData* face = f.body().face();
    straight = face != nullptr && face->surface->kind() == kernel::SurfaceKind::Plane;
  }
  if (straight) {
    for (const kernel::Shape& v : kernel::Explorer(shape, kernel::ShapeKind::Vertex)) {
      const kernel::Vec3 q = kernel::vertex_point(v);
      p.push_back({q.x(), q.y()});
    }
  } else {
    kernel::TessellationOptions options;
    options.chordal_tolerance = chordal;
    auto mesh = kernel::tessellate(shape, options);
    if (!mesh.ok()) return {};
    for (const kernel::Vec3& v : mesh->vertices) p.push_back({v.x(), v.y()});
  }
  std::sort(p.begin(), p.end());
  p.erase(std::unique(p.begin(), p.end()), p.end());
  if (p.size() < 3) return p;
  auto cross = [](const auto& o, const auto& a, const auto& b) {
    return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
  };
  std::vector<std::array<double, 2>> hull(2 * p.size());
  std::size_t k = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {  // lower chain
    while (k >= 2 && cross(hull[k - 2], hull[k - 1], p[i]) <= 0) --k;
    hull[k++] = p[i];
  }
  for (std::size_t i = p.size() - 1, t = k + 1; i-- > 0;) {  // upper chain
    while (k >= t && cross(hull[k - 2], hull[k - 1], p[i]) <= 0) --k;
    hull[k++] = p[i];
  }
  hull.resize(k - 1);
  return hull;
}

}  // namespace

Failure run_index_job(const Job& job, const std::filesystem::path& run_dir,
                      const config::Config& config, JobQueue& queue, const Logger& log,
                      std::string& result, StageTimings* timings) {
  StageTimings own;  // this job's stages go in timings.json too, however the caller keeps them
  if (timings == nullptr) timings = &own;
  ops::StageClock clock(timings);
  clock.enter("read");
  const std::string& run = config.run.name;
  Failure failure;
  const auto results = queue.results(failure);
  if (!failure.ok()) return failure;
  std::vector<DeadJob> dead;
  for (DeadJob& d : queue.dead_jobs(failure)) {
    if (is_job_of_run(d.key, run)) dead.push_back(std::move(d));
  }
  if (!failure.ok()) return failure;
  const auto fits = done_records(results, "fit", run);
  const auto cells = done_records(results, "assemble", run);
  // Each cell's manifest, read once: its index (merged below) and its files (published).
  std::vector<ordered_json> cell_manifests;
  for (const auto& [key, record] : cells) {
    const std::string cell_manifest = record.at("manifest").at("key").get<std::string>();
    std::string text;
    if (Failure f = read_file_bytes(run_dir / cell_manifest, text); !f.ok()) return f;
    cell_manifests.push_back(ordered_json::parse(text, nullptr, false));
    if (cell_manifests.back().is_discarded()) {
      return {ErrorCode::Internal, cell_manifest + ": not JSON"};
    }
  }

  // One frame for the run: its origin is the smallest cell corner.
  kernel::Vec3 origin = kernel::Vec3::Zero();
  bool first = true;
  for (const auto& [key, record] : cells) {
    const auto& o = record.at("origin");
    const kernel::Vec3 corner(o[0].get<double>(), o[1].get<double>(), 0.0);
    if (first) origin = corner;
    origin = origin.cwiseMin(corner);
    first = false;
  }
  // The run's CRS as the advance that enqueued this job chose it (the first done tile's in
  // run order); tiles in another CRS were left out of every cell.
  const auto payload = ordered_json::parse(job.payload, nullptr, false);
  const std::string crs_text = payload.is_object() ? payload.value("crs", "") : std::string();
  RunObjects objects;
  std::string datum_transformation;   // how the run's CRS reaches WGS 84 (3D Tiles, ENU frames)
  std::string height_transformation;  // how its heights become ellipsoidal (a geoid model)
  if (!crs_text.empty()) {
    auto crs = geo::crs_from_config(crs_text);
    if (crs.ok()) datum_transformation = crs->datum.to_wgs84_source;
    if (crs.ok() && crs->vertical) height_transformation = crs->vertical->to_ellipsoidal_source;
    if (crs.ok() && crs->epsg > 0) objects.crs = std::move(crs).value();
  }
  objects.origin = objects.crs ? origin : kernel::Vec3::Zero();
  ordered_json tiles_left_out = ordered_json::array();
  for (const auto& [key, record] : fits) {
    if (record.value("crs", "") != crs_text) {
      tiles_left_out.push_back(record.value("input", key) + ": CRS " + record.value("crs", "") +
                               " differs from the run's " + crs_text);
    }
  }
  clock.enter("index");
  bool all_blocks = true;
  for (const auto& [key, record] : cells) {
    const auto& o = record.at("origin");
    const kernel::Vec3 offset =
        kernel::Vec3(o[0].get<double>(), o[1].get<double>(), 0.0) - objects.origin;
    for (const auto& entry : record.at("objects")) {
      const std::string object_key = entry.at("key").get<std::string>();
      if (!is_safe_key(object_key)) return {ErrorCode::Internal, "unsafe object key " + object_key};
      auto model = kernel::read_native_model_file(run_dir / object_key);
      if (!model.ok()) {
        return failure_of(model.error(), (run_dir / object_key).string());
      }
      IndexObject io;
      io.id = entry.at("id").get<std::string>();
      io.cell = record.at("cell").get<std::string>();
      io.model = std::move(model).value();
      if (entry.contains("error") && entry.at("error").is_string()) {
        io.fuse_error = entry.at("error").get<std::string>();
      }
      if (entry.contains("footprint_id") && entry.at("footprint_id").is_string()) {
        io.footprint_id = entry.at("footprint_id").get<std::string>();
      }
      if (entry.contains("escalation") && entry.at("escalation").is_object()) {
        const ordered_json& e = entry.at("escalation");
        io.escalation = assembly::AssembledObject::Escalation{
            snap_options(e.at("snap_distance").get<double>(),
                         e.at("snap_angle_degrees").get<double>()),
            e.at("reason").get<std::string>()};
      }
      if (!offset.isZero(0.0)) move_model(io.model, kernel::Location::translation(offset));
      bool has_blocks = false;
      if (Failure f =
              read_blocks(run_dir, entry, kernel::Location::translation(offset), io, has_blocks);
          !f.ok()) {
        return f;
      }
      all_blocks = all_blocks && has_blocks;
      if (Failure f = read_model_fit(entry, io.model_fit); !f.ok()) return f;
      std::map<std::string, geo::FitQuality> quality;
      for (const auto& p : entry.at("primitives")) {
        const ordered_json& q = p.at("quality");
        if (!q.is_object()) continue;
        auto fq = geo::parse_fit_quality(q.dump());
        if (fq.ok()) quality[p.at("label").get<std::string>()] = fq.value();
      }
      io.primitives = model_primitives(
          io.model, [&quality](const std::string& label) -> std::optional<geo::FitQuality> {
            const auto it = quality.find(label);
            if (it == quality.end()) return std::nullopt;
            return it->second;
          });
      objects.objects.push_back(std::move(io));
    }
  }
  // Records written before blocks were kept: compute them all here, as the cells would have.
  const RunExportOptions settings = jobs::export_options(config);
  if (!all_blocks) {
    add_building_lods(objects.objects, settings.chordal_tolerance, settings.linear_tolerance);
  }
  // The relations of objects of one cell as their cell classified them (all cells must give
  // them; a record of an older worker makes the index classify every pair itself).
  {
    std::map<std::string, std::size_t> index_of;
    for (std::size_t i = 0; i < objects.objects.size(); ++i) index_of[objects.objects[i].id] = i;
    std::vector<ObjectRelation> known;
    bool all_found = true;
    for (const auto& [key, record] : cells) {
      bool found = false;
      if (Failure f = read_relations(record, index_of, known, found); !f.ok()) return f;
      all_found = all_found && found;
    }
    if (all_found) objects.cell_relations = std::move(known);
  }
  // The cells' indexes already hold every object's rows, in the CRS: the run's index merges
  // them (ids offset, primitives' placements moved into the run frame) rather than building
  // them again. A cell whose index is not as its manifest says, a run without an EPSG CRS
  // (the cells' files are then in cell coordinates) or older records: built again.
  if (objects.crs && all_blocks && objects.cell_relations) {
    std::string why;
    for (std::size_t c = 0; c < cells.size(); ++c) {
      const ordered_json& record = cells[c].second;
      const ordered_json& cm = cell_manifests[c];
      const std::string cell_manifest = record.at("manifest").at("key").get<std::string>();
      if (!cm.is_object() || !cm.contains("index") || !cm["index"].is_object() ||
          !cm["index"].contains("key") || !cm["index"].contains("sha256")) {
        why = cell_manifest + " names no index";
        break;
      }
      const std::string index_key = cm["index"]["key"].get<std::string>();
      if (!is_safe_key(index_key)) {
        why = cell_manifest + ": unsafe index key " + index_key;
        break;
      }
      const std::filesystem::path index_path =
          run_dir / std::filesystem::path(cell_manifest).parent_path() / index_key;
      std::string sha;
      std::uint64_t bytes = 0;
      if (Failure f = file_sha256(index_path, sha, bytes);
          !f.ok() || sha != cm["index"]["sha256"]) {
        why = index_path.string() + " is not the index its manifest names";
        break;
      }
      const auto& o = record.at("origin");
      objects.cell_indexes.push_back(
          {index_path, kernel::Vec3(o[0].get<double>(), o[1].get<double>(), 0.0) - objects.origin});
      if (cm["index"].contains("warnings")) {
        for (const auto& w : cm["index"]["warnings"]) {
          objects.cell_index_warnings.push_back(w.get<std::string>());
        }
      }
    }
    if (!why.empty()) {
      log.info("index", "the cells' indexes are built again", {{"reason", why}});
      objects.cell_indexes.clear();
      objects.cell_index_warnings.clear();
    }
  }
  RunIndexReport index;
  if (Failure f = write_run_index(settings, objects, run_dir, index); !f.ok()) return f;
  log.info("index", "written",
           {{"key", index.key}, {"objects", std::to_string(index.stats.objects)}});

  clock.enter("publish");
  std::string tileset;
  std::size_t tile_children = 0;
  if (Failure f = root_tileset(run_dir, cells, tileset, tile_children); !f.ok()) return f;
  ordered_json root_tiles = nullptr;
  if (tile_children > 0) {
    if (Failure f = write_file_atomic(run_dir / "tiles/tileset.json", tileset); !f.ok()) return f;
    root_tiles = {{"key", "tiles/tileset.json"},
                  {"sha256", sha256_hex(tileset)},
                  {"bytes", tileset.size()},
                  {"cells", tile_children}};
  }

  // The manifest: every job's record (timings moved to timings.json), dead jobs, the cells'
  // manifests and the run-level files. Written last: a reader who finds it finds the rest.
  ordered_json manifest = manifest_head(jobs::manifest_identity(config), "city");
  manifest["crs"] = crs_text;
  manifest["crs_to_wgs84"] = datum_transformation;
  manifest["crs_heights"] = height_transformation;
  manifest["origin"] = {objects.origin.x(), objects.origin.y(), objects.origin.z()};
  manifest["cell_size"] = config.city.cell_size;
  manifest["halo"] = config.city.halo;
  JobRecords records;
  for (const auto* group : {&fits, &cells}) {
    for (const auto& [key, stored] : *group) records.add(key, stored);
  }
  long long primitives = 0, points = 0, assigned = 0;
  std::map<std::string, long long> per_type;
  for (const auto& [key, record] : fits) {
    primitives += record.value("primitives", 0LL);
    points += record.value("points", 0LL);
    assigned += record.value("assigned_points", 0LL);
    for (const auto& [type, n] : record.at("per_type").items())
      per_type[type] += n.get<long long>();
  }
  ordered_json cell_list = ordered_json::array();
  long long object_count = 0;
  ordered_json problems = ordered_json::array();
  for (const auto& [key, record] : cells) {
    object_count += static_cast<long long>(record.at("objects").size());
    cell_list.push_back({{"cell", record.at("cell")},
                         {"manifest", record.at("manifest")},
                         {"objects", record.at("objects").size()}});
    for (const auto& p : record.at("problems")) {
      problems.push_back(record.at("cell").get<std::string>() + ": " + p.get<std::string>());
    }
  }
  for (const auto& t : tiles_left_out) problems.push_back(t);
  manifest["totals"] = {{"tiles", fits.size()},        {"points", points},
                        {"assigned_points", assigned}, {"primitives", primitives},
                        {"per_type", per_type},        {"cells", cells.size()},
                        {"objects", object_count}};
  manifest["cells"] = cell_list;
  manifest["index"] = index_entry(index);
  manifest["tiles"] = root_tiles;
  manifest["problems"] = problems;

  // This job's own line of timings.json (a job's record has its timings only once it is
  // done): its stages up to here, before the report, the manifest and the upload.
  clock.stop();
  {
    double seconds = 0.0;
    for (const auto& stage : timings->seconds) seconds += stage.second;
    ordered_json entry = {{"key", job.key}};
    entry.update(timings_json(*timings, seconds, "", job.attempts, ops::peak_resident_mib()));
    entry["until"] = "report";
    records.timings.push_back(std::move(entry));
  }
  clock.enter("publish");

  // The report (report.h): figures of the run, the cells' footprints and 3D views.
  ReportInput report;
  report.run = run;
  report.crs = crs_text;
  report.primitives_per_type = per_type;
  long long fused = 0, unfused = 0;
  std::size_t next_object = 0;
  for (const auto& [key, record] : cells) {
    ReportCell rc;
    rc.id = record.at("cell").get<std::string>();
    const auto& o = record.at("origin");
    const double x0 = o[0].get<double>() - objects.origin.x();
    const double y0 = o[1].get<double>() - objects.origin.y();
    rc.bounds = {x0, y0, x0 + config.city.cell_size, y0 + config.city.cell_size};
    for (const auto& entry : record.at("objects")) {
      ReportObject ro;
      ro.id = entry.at("id").get<std::string>();
      for (const auto& p : entry.at("primitives")) {
        ro.primitive_types.push_back(p.at("type").get<std::string>());
        const ordered_json& q = p.at("quality");
        if (q.is_object()) report.fit_rms.push_back(q.at("rms").get<double>());
      }
      ro.volume = entry.at("volume").get<double>();
      ro.valid = entry.at("fused").get<bool>();
      (ro.valid ? fused : unfused) += 1;
      if (next_object < objects.objects.size()) {
        const IndexObject& io = objects.objects[next_object];
        auto hull = footprint_hull(io.model.shape, 0.05);
        if (!hull.empty()) ro.footprint.push_back(std::move(hull));
        ro.building = report_building(io, objects.origin.z());
      }
      ++next_object;
      rc.objects.push_back(std::move(ro));
    }
    if (record.contains("tiles") && record["tiles"].is_string()) {
      const std::string tiles_key = record["tiles"].get<std::string>();
      rc.glb_path =
          (run_dir / std::filesystem::path(tiles_key).parent_path() / "model.glb").string();
    }
    for (const auto& p : record.at("problems")) rc.validation.push_back(p.get<std::string>());
    report.cells.push_back(std::move(rc));
  }
  report.validation_counts = {{"tiles fitted", static_cast<long long>(fits.size())},
                              {"cells", static_cast<long long>(cells.size())},
                              {"objects fused and valid", fused},
                              {"objects left unfused (fuse failed)", unfused},
                              {"run index objects", static_cast<long long>(index.stats.objects)},
                              {"dead jobs", static_cast<long long>(dead.size())}};
  for (const DeadJob& d : dead) report.dead_jobs.push_back(d.key + ": " + d.last_error);
  std::map<std::string, double> stage_totals;
  std::vector<std::string> stage_order;
  for (const auto& t : records.timings) {
    // The job of the highest peak memory, in the same pass.
    if (const auto peak = t.find("peak_rss_mib");
        peak != t.end() && peak->is_number() &&
        (report.peak_job.empty() || peak->get<double>() > report.peak_rss_mib)) {
      report.peak_job = t.value("key", std::string());
      report.peak_rss_mib = peak->get<double>();
    }
    if (!t.contains("stages")) continue;
    for (const auto& [stage, seconds] : t["stages"].items()) {
      if (!stage_totals.count(stage)) stage_order.push_back(stage);
      stage_totals[stage] += seconds.get<double>();
    }
  }
  for (const std::string& stage : stage_order)
    report.stage_seconds.emplace_back(stage, stage_totals[stage]);
  ReportFiles report_files;
  if (Failure f = write_run_report(report, run_dir, report_files); !f.ok()) return f;
  ordered_json report_entries = ordered_json::array();
  for (const std::string& key : report_files.keys) {
    ordered_json entry;
    if (Failure f = describe_file(run_dir, key, entry); !f.ok()) return f;
    report_entries.push_back(std::move(entry));
  }
  manifest["report"] = {{"key", "report/index.html"},
                        {"files", report_entries},
                        {"not_deterministic", report_files.nondeterministic_keys}};
  std::string manifest_text;
  if (Failure f =
          write_run_manifest(run_dir, run, std::move(manifest), records, dead, manifest_text);
      !f.ok()) {
    return f;
  }
  // Only what the manifests name is published (leftovers of an earlier run in the same
  // directory, e.g. cells of another cell size, stay local).
  std::set<std::string> listed = {"manifest.json", "timings.json", "tiles.json", index.key};
  if (tile_children > 0) listed.insert("tiles/tileset.json");
  for (const auto& entry : report_entries) listed.insert(entry.at("key").get<std::string>());
  for (const std::string& key : report_files.nondeterministic_keys) listed.insert(key);
  for (const auto& [key, record] : fits) {
    listed.insert(record.at("scene").at("key").get<std::string>());
    // The points the objects were measured against (model_fit.h): the model fit reproducible.
    if (record.contains("structure_points")) {
      listed.insert(record.at("structure_points").at("key").get<std::string>());
    }
  }
  for (std::size_t c = 0; c < cells.size(); ++c) {
    const ordered_json& record = cells[c].second;
    const ordered_json& cm = cell_manifests[c];
    const std::string cell_manifest = record.at("manifest").at("key").get<std::string>();
    listed.insert(cell_manifest);
    const std::string dir = std::filesystem::path(cell_manifest).parent_path().string();
    for (const auto& file : cm.at("files"))
      listed.insert(dir + "/" + file.at("key").get<std::string>());
    for (const auto& object : record.at("objects")) {
      listed.insert(object.at("key").get<std::string>());
      for (const std::string& block : block_keys(object)) listed.insert(block);
    }
  }
  if (Failure f =
          publish::publish_run_directory(jobs::publish_target(config), run_dir, log, &listed);
      !f.ok())
    return f;

  ordered_json record;
  record["manifest"] = {{"key", "manifest.json"},
                        {"sha256", sha256_hex(manifest_text)},
                        {"bytes", manifest_text.size()}};
  record["cells"] = cells.size();
  record["objects"] = object_count;
  record["dead"] = dead.size();
  result = record.dump();
  return {};
}

}  // namespace csgtile::worker::city::detail
