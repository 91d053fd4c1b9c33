// The `assemble` job of a city run: the primitives of a cell and its halo → unified objects
// (kernel/assembly) anchored in the cell → the cell's native model, topology index,
// CityJSONSeq, 3D Tiles and manifest (city_jobs.h).

#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <map>

#include "city/block_records.h"
#include "city/city_internal.h"
#include "city/model_fit.h"
#include "city/relation_records.h"
#include "csgtile/assembly/assembly.h"
#include "csgtile/geo/crs.h"
#include "csgtile/geo/scene.h"
#include "csgtile/kernel/check.h"
#include "csgtile/kernel/mass_properties.h"
#include "csgtile/kernel/native_format.h"
#include "csgtile/kernel/primitives.h"
#include "csgtile/kernel/tessellation.h"
#include "csgtile/worker/publish.h"
#include "export/cityjson_seq.h"
#include "export/manifest.h"
#include "export/run_index.h"
#include "export/tileset.h"
#include "export_settings.h"
#include "ops/stage_clock.h"
#include "snap_json.h"

namespace csgtile::worker::city::detail {

namespace {

/// A primitive read for the cell: its spec in the cell frame, label, fit quality and its box
/// in CRS coordinates (computed in the tile frame, as the fit job computed its anchor).
struct CellPrimitive {
  assembly::AssemblyPrimitive primitive;
  std::optional<geo::FitQuality> quality;
  kernel::BoundingBox crs_box;
  std::string building;  // its footprint's id; "" for a derived outline
};

// The structure points a fit job published (its record's "structure_points"; none for a
// record without them), moved by `to_cell` into the cell frame, those in the cell's halo
// appended to `out`. Errors: Io, InputInvalid (a file that does not match its hash or is no
// points file), Internal (an unsafe key).
Failure read_cell_points(const std::filesystem::path& run_dir, const ordered_json& fit,
                         const kernel::Vec3& to_cell, double size, double halo,
                         std::vector<kernel::Vec3>& out) {
  if (!fit.contains("structure_points")) return {};
  const ordered_json& entry = fit.at("structure_points");
  const std::string key = entry.at("key").get<std::string>();
  if (!is_safe_key(key)) return {ErrorCode::Internal, "unsafe points key " + key};
  std::string bytes;
  if (Failure f = read_file_bytes(run_dir / key, bytes); !f.ok()) return f;
  if (sha256_hex(bytes) != entry.at("sha256").get<std::string>()) {
    return {ErrorCode::InputInvalid, (run_dir / key).string() + ": does not match its SHA-256"};
  }
  std::vector<kernel::Vec3> tile_points;
  if (Failure f = decode_points(bytes, (run_dir / key).string(), tile_points); !f.ok()) return f;
  // The halo in the cell frame: the cell's corner is its origin.
  const double lo = -halo, hi = size + halo;
  for (const kernel::Vec3& p : tile_points) {
    const kernel::Vec3 q = p + to_cell;
    if (q.x() >= lo && q.x() <= hi && q.y() >= lo && q.y() <= hi) out.push_back(q);
  }
  return {};
}

// The noise of an object's fit: the median σ of its primitives' fits (0 when none gave one).
double median_sigma(const std::vector<CellPrimitive>& prims, const std::vector<int>& of) {
  std::vector<double> s;
  for (int i : of) {
    const auto& q = prims[static_cast<std::size_t>(i)].quality;
    if (q && q->sigma && *q->sigma > 0.0) s.push_back(*q->sigma);
  }
  if (s.empty()) return 0.0;
  std::sort(s.begin(), s.end());
  return s.size() % 2 == 1 ? s[s.size() / 2] : 0.5 * (s[s.size() / 2 - 1] + s[s.size() / 2]);
}

ordered_json quality_json(const std::optional<geo::FitQuality>& q) {
  if (!q) return nullptr;
  return ordered_json::parse(geo::fit_quality_to_json(*q));
}

}  // namespace

Failure run_assemble_job(const Job& job, const std::filesystem::path& run_dir,
                         const config::Config& config, std::string& result, StageTimings* timings,
                         std::stop_token stop) {
  ops::StageClock clock(timings);
  clock.enter("read");
  const auto payload = ordered_json::parse(job.payload, nullptr, false);
  if (payload.is_discarded() || !payload.contains("cell") || !payload.contains("fits")) {
    return {ErrorCode::Internal, "job " + job.key + " has a malformed payload"};
  }
  const kernel::GridCell cell{payload.at("column").get<std::int64_t>(),
                              payload.at("row").get<std::int64_t>()};
  const std::string name = cell.name();
  const kernel::Grid grid = run_grid(config);
  const double size = grid.size, halo = grid.halo;
  const kernel::Vec3 cell_origin3(grid.edge_x(cell.column), grid.edge_y(cell.row), 0.0);

  // Primitives of every tile near the cell, in tile order, those meeting the halo; the tiles'
  // structure points in the halo, in the cell frame.
  std::vector<CellPrimitive> prims;
  std::vector<kernel::Vec3> points;
  for (const auto& fit : payload.at("fits")) {
    const std::string key = fit.at("scene").at("key").get<std::string>();
    if (!is_safe_key(key)) return {ErrorCode::Internal, "unsafe scene key " + key};
    std::string text;
    if (Failure f = read_file_bytes(run_dir / key, text); !f.ok()) return f;
    if (sha256_hex(text) != fit.at("scene").at("sha256").get<std::string>()) {
      return {ErrorCode::InputInvalid, (run_dir / key).string() + ": does not match its SHA-256"};
    }
    auto scene = geo::parse_scene(text);
    if (!scene.ok()) return {ErrorCode::InputInvalid, key + ": " + scene.error().message};
    const auto& o = fit.at("origin");
    const kernel::Vec3 tile_origin(o[0].get<double>(), o[1].get<double>(), o[2].get<double>());
    const std::string tile = "t" + std::to_string(fit.at("tile").get<long long>());
    if (Failure f = read_cell_points(run_dir, fit, tile_origin - cell_origin3, size, halo, points);
        !f.ok()) {
      return f;
    }
    for (std::size_t i = 0; i < scene->primitives.size(); ++i) {
      const geo::ScenePrimitive& p = scene->primitives[i];
      // A clipped primitive lies inside its plain solid (no Boolean to build): one whose plain
      // solid, grown by the tolerance, stays clear of the halo is skipped unbuilt.
      if (!p.spec.clips.empty()) {
        kernel::PrimitiveSpec plain = p.spec;
        plain.clips.clear();
        kernel::BoundingBox outer =
            primitive_crs_box(plain, tile_origin, config.kernel.linear_tolerance);
        outer.enlarge(config.kernel.linear_tolerance);
        if (!outer.empty() && !grid.meets_halo(outer, cell)) continue;
      }
      const kernel::BoundingBox box =
          primitive_crs_box(p.spec, tile_origin, config.kernel.linear_tolerance);
      if (box.empty()) continue;  // the fit job left out primitives that do not build
      if (!grid.meets_halo(box, cell)) continue;
      CellPrimitive cp;
      cp.primitive.spec = p.spec;
      cp.primitive.spec.placement =
          kernel::Location::translation(tile_origin - cell_origin3) * p.spec.placement;
      cp.primitive.label = tile + "-" + (p.id.empty() ? "p" + std::to_string(i) : p.id);
      cp.primitive.group = geo::assembly_group(p, tile);
      cp.building = p.building;
      cp.quality = p.quality;
      cp.crs_box = box;
      prims.push_back(std::move(cp));
    }
  }

  clock.enter("assemble");
  std::vector<assembly::AssemblyPrimitive> input;
  input.reserve(prims.size());
  for (const CellPrimitive& p : prims) input.push_back(p.primitive);
  assembly::AssemblyOptions options;
  options.tolerance = config.kernel.linear_tolerance;
  options.voxel_size = config.city.voxel_size;
  options.threads = config.run.threads;
  options.snap = snap_options(config.city.snap_distance, config.city.snap_angle_degrees);
  options.escalate_to = config.city.snap_escalate_to;
  options.interrupt.stop = std::move(stop);
  options.object_time_limit = config.city.building_timeout_seconds;
  // Only the objects anchored in this cell are fused: the least of their primitives' anchor
  // cells (each the cell of a primitive's minimum corner, computed as the fit job computed
  // it), so the object's cell is one the fits named and that has an assemble job. The
  // halo's other objects are their own cells' work.
  options.anchor.reserve(prims.size());
  for (const CellPrimitive& p : prims) {
    const kernel::GridCell c = grid.cell_of(p.crs_box.min.x(), p.crs_box.min.y());
    options.anchor.push_back(c < cell ? -1 : c == cell ? 0 : 1);
  }
  auto assembled = assembly::assemble(input, options);
  if (!assembled.ok()) {
    return failure_of(assembled.error(), name);
  }
  const assembly::Assembly& a = assembled.value();

  clock.enter("publish");
  // Problems of the objects this cell keeps (the assembly also names objects of the halo,
  // which their own cells report) and of primitives that could not be built.
  ordered_json problems = ordered_json::array();
  for (const std::string& p : a.problems) {
    if (p.rfind("object ", 0) != 0) problems.push_back(p);
  }
  std::vector<const assembly::AssembledObject*> kept;
  for (const assembly::AssembledObject& object : a.objects) {
    kernel::BoundingBox box;
    for (int i : object.primitives) box.add(prims[static_cast<std::size_t>(i)].crs_box);
    if (!grid.within_halo(box, cell)) {
      problems.push_back("object " + object.id + " reaches past the halo of cell " + name +
                         " (city.halo " + ordered_json(halo).dump() +
                         "): it may be cut; raise city.halo");
    }
    if (!object.fused) {
      problems.push_back("object " + object.id + " not fused: " + object.error +
                         (object.timed_out ? " (city.building_timeout_seconds)" : ""));
    }
    kept.push_back(&object);
  }

  // Each object's check (once, for every export) and its native bytes, on the run's threads.
  tbb::task_arena arena(config.run.threads > 0 ? config.run.threads : tbb::task_arena::automatic);
  std::vector<char> valid(kept.size(), 0);
  std::vector<std::string> native(kept.size());
  // Each object tessellated once for its blocks and every export (CityJSON, glTF, the index's
  // curved boundaries), which each tessellated it again before; left null where it fails,
  // for each to report.
  const double chordal = config.kernel.chordal_tolerance;
  std::vector<std::shared_ptr<const kernel::Mesh>> object_meshes(kept.size());
  arena.execute([&] {
    tbb::parallel_for(std::size_t{0}, kept.size(), [&](std::size_t i) {
      if (auto mesh = kernel::shared_tessellation(kept[i]->model.shape, chordal); mesh.ok()) {
        object_meshes[i] = std::move(mesh).value();
      }
      // A fused object's Boolean checked its result already (work done twice before).
      valid[i] = kept[i]->checked || kernel::check_shape(kept[i]->model.shape).valid() ? 1 : 0;
      native[i] = kernel::write_native_model(kept[i]->model);
    });
  });
  RunObjects objects;
  ObjectBatch objects_out(run_dir);  // the objects' and their blocks' models, flushed together
  ordered_json object_records = ordered_json::array();
  std::vector<assembly::AssembledObject> kept_objects;
  long long invalid = 0;
  for (std::size_t k = 0; k < kept.size(); ++k) {
    const assembly::AssembledObject* object = kept[k];
    IndexObject io;
    io.id = object->id;
    io.cell = name;
    io.model = object->model;
    if (!object->fused) io.fuse_error = object->error;
    io.escalation = object->escalation;
    io.valid = valid[k] != 0;
    io.mesh = std::move(object_meshes[k]);
    io.mesh_tolerance = chordal;
    // Every primitive of an object has its building (assembly_group).
    io.footprint_id = prims[static_cast<std::size_t>(object->primitives.front())].building;
    const ordered_json escalation = escalation_json(io.escalation);
    ordered_json prim_records = ordered_json::array();
    std::map<std::string, const CellPrimitive*> by_label;
    for (int i : object->primitives) {
      const CellPrimitive& p = prims[static_cast<std::size_t>(i)];
      by_label[p.primitive.label] = &p;
      prim_records.push_back({{"label", p.primitive.label},
                              {"type", kernel::primitive_type_name(p.primitive.spec.type)},
                              {"quality", quality_json(p.quality)}});
    }
    io.primitives = model_primitives(
        object->model, [&by_label](const std::string& label) -> std::optional<geo::FitQuality> {
          const auto it = by_label.find(label);
          return it == by_label.end() ? std::nullopt : it->second->quality;
        });
    PublishedModel published;
    if (Failure f = publish_native(std::move(native[k]), objects_out, published); !f.ok()) {
      return f;
    }
    if (!object->fused) ++invalid;
    object_records.push_back(
        {{"id", object->id},
         {"key", published.key},
         {"sha256", published.sha256},
         {"bytes", published.bytes},
         {"fused", object->fused},
         {"error", object->fused ? ordered_json() : ordered_json(object->error)},
         {"escalation", escalation},
         {"footprint_id", io.footprint_id.empty() ? ordered_json() : ordered_json(io.footprint_id)},
         {"volume", object->volume},
         {"primitives", prim_records}});
    objects.objects.push_back(std::move(io));
    kept_objects.push_back(*object);
  }

  // The LoD1.2 / LoD1.3 block models are modelling (Booleans of the buildings' footprint
  // extrusions) and the model's distance to its points is measuring: each its own stage, so
  // that `publish` times writing the cell's outputs.
  clock.enter("blocks");
  add_building_lods(objects.objects, config.kernel.chordal_tolerance,
                    config.kernel.linear_tolerance);
  // How far each object's points lie from its model (3DBAG's RMSE of a LoD2.2).
  clock.enter("measure");
  long long points_over_none = 0;
  {
    std::vector<const kernel::Shape*> shapes;
    std::vector<std::shared_ptr<const kernel::Mesh>> meshes;
    std::vector<double> sigma;
    for (std::size_t i = 0; i < objects.objects.size(); ++i) {
      shapes.push_back(&objects.objects[i].model.shape);
      meshes.push_back(shared_mesh(objects.objects[i], config.kernel.chordal_tolerance));
      sigma.push_back(median_sigma(prims, kept_objects[i].primitives));
    }
    const auto fits = measure_model_fit(shapes, sigma, points, config.kernel.chordal_tolerance,
                                        points_over_none, meshes);
    for (std::size_t i = 0; i < objects.objects.size(); ++i) {
      objects.objects[i].model_fit = fits[i];
      object_records[i]["model_fit"] = model_fit_json(fits[i]);
    }
  }
  // The relations of the cell's objects (party walls, overlaps) are modelling too: the exact
  // Booleans of every pair whose boxes meet. The cell's index and its record take them.
  clock.enter("relations");
  {
    std::vector<kernel::Shape> solids;
    solids.reserve(objects.objects.size());
    for (const IndexObject& o : objects.objects) solids.push_back(o.model.shape);
    objects.cell_relations =
        compute_relations(solids, config.kernel.linear_tolerance, config.run.threads);
  }
  // The blocks go in the records: the index job reads them rather than computing them again.
  clock.enter("publish");
  for (std::size_t i = 0; i < objects.objects.size(); ++i) {
    ordered_json blocks;
    if (Failure f = publish_blocks(objects.objects[i], objects_out, blocks); !f.ok()) return f;
    object_records[i]["blocks"] = std::move(blocks);
  }
  if (Failure f = objects_out.commit(); !f.ok()) return f;

  // The cell's files, in the cell frame (origin: the cell's corner).
  const std::string crs_text = payload.value("crs", "");
  if (!crs_text.empty()) {
    auto crs = geo::crs_from_config(crs_text);
    if (crs.ok() && crs->epsg > 0) {
      objects.crs = std::move(crs).value();
      objects.origin = cell_origin3;
    } else {
      problems.push_back("the tiles' CRS " + crs_text +
                         " has no EPSG code: the cell's exports are in cell coordinates");
    }
  }
  const std::string dir_key = "cells/" + name;
  const std::filesystem::path cell_dir = run_dir / dir_key;
  auto city = assembly::city_model(kept_objects);
  if (!city.ok()) return failure_of(city.error(), name);
  // The four files read the same objects and write nothing the others read: the index (its
  // rows streamed, two thirds of the time) beside the other three in turn, on the run's
  // threads — each one's bytes the same whatever runs beside it; one of the three large
  // buffers (CityJSONSeq, native model, glTF) held at a time. Failures in a fixed order.
  const RunExportOptions settings = jobs::export_options(config);
  std::string model_sha256;
  std::size_t model_size = 0;
  RunIndexReport index;
  CityJsonReport cityjson;
  TilesReport tiles;
  std::array<Failure, 4> written;
  arena.execute([&] {
    tbb::parallel_invoke([&] { written[0] = write_run_index(settings, objects, cell_dir, index); },
                         [&] {
                           written[1] = write_run_cityjson(settings, objects, cell_dir, cityjson);
                           {
                             const std::string model_bytes =
                                 kernel::write_native_model(city.value());
                             written[2] = write_file_atomic(cell_dir / "model.csgt", model_bytes);
                             model_sha256 = sha256_hex(model_bytes);
                             model_size = model_bytes.size();
                           }
                           written[3] = write_run_tiles(settings, objects, cell_dir, tiles);
                         });
  });
  for (const Failure& f : written) {
    if (!f.ok()) return f;
  }
  for (const std::string& w : index.stats.warnings) problems.push_back("index: " + w);
  for (const std::string& w : cityjson.stats.warnings) problems.push_back("cityjson: " + w);
  for (const std::string& w : tiles.warnings) problems.push_back("tiles: " + w);

  // The cell manifest names every file of the cell with its hash (as its writer hashed the
  // bytes it wrote and flushed); written last.
  ordered_json files = ordered_json::array();
  const auto file_entry = [&files](const std::string& key, const std::string& sha256,
                                   std::uint64_t bytes) {
    files.push_back({{"key", key}, {"sha256", sha256}, {"bytes", bytes}});
  };
  file_entry("model.csgt", model_sha256, model_size);
  file_entry(index.key, index.sha256, index.bytes);
  file_entry(cityjson.key, cityjson.sha256, cityjson.bytes);
  if (tiles.written) {
    file_entry(tiles.content, tiles.content_sha256, tiles.content_bytes);
    file_entry(tiles.key, tiles.sha256, tiles.bytes);
  }
  const assembly::AssemblyStats& s = a.stats;
  ordered_json stats = assembly_counts_json(s);
  stats["objects_reached"] = s.components;
  stats["objects"] = kept.size();
  stats["objects_unfused"] = invalid;
  stats["structure_points_in_halo"] = points.size();
  stats["structure_points_over_no_object"] = points_over_none;
  // The run manifest's head and export entries (export/manifest.h), then the cell's own.
  ordered_json manifest = manifest_head(jobs::manifest_identity(config), "cell");
  manifest["cell"] = name;
  manifest["origin"] = {cell_origin3.x(), cell_origin3.y(), 0.0};
  manifest["crs"] = crs_text;
  manifest["files"] = files;
  manifest["objects"] = object_records;
  manifest["stats"] = stats;
  manifest["index"] = index_entry(index);
  manifest["cityjson"] = cityjson_entry(cityjson);
  manifest["tiles"] = tiles_entry(tiles);
  if (!tiles.written) manifest["tiles_skipped"] = tiles.skipped;
  manifest["problems"] = problems;
  const std::string manifest_text = manifest.dump(2) + "\n";
  if (Failure f = write_file_atomic(cell_dir / "manifest.json", manifest_text); !f.ok()) return f;

  ordered_json record;
  record["cell"] = name;
  record["column"] = cell.column;
  record["row"] = cell.row;
  record["origin"] = {cell_origin3.x(), cell_origin3.y(), 0.0};
  record["manifest"] = {{"key", dir_key + "/manifest.json"},
                        {"sha256", sha256_hex(manifest_text)},
                        {"bytes", manifest_text.size()}};
  record["tiles"] = tiles.written ? ordered_json(dir_key + "/" + tiles.key) : ordered_json();
  record["objects"] = object_records;
  // Its objects' relations: the run index takes them instead of classifying them again.
  record["relations"] = relations_json(index.stats.relation_pairs, objects.objects);
  record["stats"] = stats;
  record["problems"] = problems;
  result = record.dump();
  return {};
}

}  // namespace csgtile::worker::city::detail
