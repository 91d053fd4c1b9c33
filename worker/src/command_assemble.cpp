// `csgtile assemble SCENE.json --out DIR [--json]`: city-scale assembly of a scene's
// primitives (kernel/assembly): broad phase, OpenVDB culling, exact tests, one fused object
// per connected group. Writes DIR/model.csgt (the city model with every object's CSG tree)
// and DIR/assembly.json (objects, contacts, statistics, problems); prints the statistics
// and the total volume. With --cell-size, each cell (or only --cell I,J) is assembled on its
// own from its primitives and a halo, into DIR/cell_I_J/.

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>

#include "commands.h"
#include "csgtile/assembly/assembly.h"
#include "csgtile/geo/scene.h"
#include "csgtile/kernel/explorer.h"
#include "csgtile/kernel/mass_properties.h"
#include "csgtile/kernel/native_format.h"
#include "csgtile/worker/errors.h"
#include "csgtile/worker/publish.h"
#include "snap_json.h"

namespace csgtile::worker::detail {

namespace {

using nlohmann::ordered_json;

struct AssembleArgs {
  std::string scene, out;
  bool json = false;
  double voxel = 0.5, tolerance = kernel::kDefaultTolerance;
  double snap_distance = 0.0, snap_degrees = 0.0, escalate_to = 0.0;
  int threads = 0;
  bool no_cull = false, no_broad = false;
  double cell_size = 0, halo = 0;
  std::vector<long long> cell;  // {i, j} or empty
};

ordered_json box_json(const kernel::BoundingBox& b) {
  if (b.empty()) return nullptr;
  return ordered_json::array({b.min.x(), b.min.y(), b.min.z(), b.max.x(), b.max.y(), b.max.z()});
}

ordered_json stats_json(const assembly::AssemblyStats& s) {
  ordered_json j = {{"primitives", s.primitives}};
  j.update(assembly_counts_json(s));
  j["objects"] = s.objects;
  j["objects_failed"] = s.objects_failed;
  j["objects_past_halo"] = s.objects_past_halo;
  j["active_voxels"] = s.active_voxels;
  j["seconds"] = {{"build", s.seconds_build},         {"broad_phase", s.seconds_broad},
                  {"voxel_culling", s.seconds_voxel}, {"exact_tests", s.seconds_exact},
                  {"fuse", s.seconds_fuse},           {"total", s.seconds_total}};
  return j;
}

// The deterministic part of a cell's result (no timings): what assembly.json holds.
ordered_json result_json(const assembly::Assembly& a,
                         const std::vector<assembly::AssemblyPrimitive>& prims, double volume) {
  ordered_json j;
  j["total_volume"] = volume;
  ordered_json objects = ordered_json::array();
  for (const auto& o : a.objects) {
    ordered_json oj;
    oj["id"] = o.id;
    ordered_json labels = ordered_json::array();
    for (int i : o.primitives) labels.push_back(prims[static_cast<std::size_t>(i)].label);
    oj["primitives"] = labels;
    oj["fused"] = o.fused;
    oj["error"] = o.fused ? ordered_json() : ordered_json(o.error);
    oj["escalation"] = escalation_json(o.escalation);
    oj["solids"] = kernel::map_child_shapes(o.model.shape, kernel::ShapeKind::Solid).size();
    oj["faces"] = kernel::map_child_shapes(o.model.shape, kernel::ShapeKind::Face).size();
    oj["volume"] = o.volume;
    oj["bbox"] = box_json(o.box);
    oj["reaches_past_halo"] = o.reaches_past_halo;
    objects.push_back(std::move(oj));
  }
  j["objects"] = std::move(objects);
  ordered_json contacts = ordered_json::array();
  for (const auto& c : a.contacts) {
    contacts.push_back({{"a", prims[static_cast<std::size_t>(c.a)].label},
                        {"b", prims[static_cast<std::size_t>(c.b)].label},
                        {"kind", kernel::interference_name(c.kind)}});
  }
  j["contacts"] = std::move(contacts);
  j["problems"] = a.problems;
  return j;
}

// Assembles one cell (or everything) into `dir`; returns the printed report.
Failure assemble_into(const std::vector<assembly::AssemblyPrimitive>& prims,
                      const assembly::AssemblyOptions& options, const std::filesystem::path& dir,
                      ordered_json& report) {
  auto result = assembly::assemble(prims, options);
  if (!result.ok()) return {ErrorCode::InputInvalid, result.error().message};
  auto model = assembly::city_model(result->objects);
  if (!model.ok()) return failure_of(model.error());
  double volume = 0;
  for (const auto& o : result->objects) volume += o.volume;
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) return {ErrorCode::Io, "cannot create " + dir.string() + ": " + ec.message()};
  if (auto s = kernel::write_native_model_file(dir / "model.csgt", model.value()); !s.ok()) {
    return {ErrorCode::Io, s.error().message};
  }
  const ordered_json body = result_json(result.value(), prims, volume);
  if (auto f = write_file_atomic(dir / "assembly.json", body.dump(1) + "\n"); !f.ok()) return f;
  report = ordered_json();
  if (options.cell) report["cell"] = {options.cell->cell.column, options.cell->cell.row};
  report["model"] = (dir / "model.csgt").string();
  report["total_volume"] = volume;
  report["statistics"] = stats_json(result->stats);
  report["problems"] = result->problems;
  return {};
}

Failure run_assemble(const AssembleArgs& args, ordered_json& report) {
  auto scene = geo::read_scene(args.scene);
  if (!scene.ok()) {
    return {
        scene.error().code == kernel::ErrorCode::IoError ? ErrorCode::Io : ErrorCode::InputInvalid,
        scene.error().message};
  }
  std::vector<assembly::AssemblyPrimitive> prims;
  std::map<std::string, int> seen;
  for (std::size_t i = 0; i < scene->primitives.size(); ++i) {
    const auto& p = scene->primitives[i];
    std::string label = p.id.empty() ? "p" + std::to_string(i) : p.id;
    if (seen.count(label)) label += "#" + std::to_string(i);  // ids must name one primitive
    seen[label] = 1;
    prims.push_back({p.spec, label, geo::assembly_group(p)});
  }
  assembly::AssemblyOptions options;
  options.voxel_size = args.voxel;
  options.tolerance = args.tolerance;
  options.threads = args.threads;
  options.snap = snap_options(args.snap_distance, args.snap_degrees);
  options.escalate_to = args.escalate_to;
  options.voxel_culling = !args.no_cull;
  options.broad_phase = !args.no_broad;
  const std::filesystem::path out = args.out;
  report = ordered_json();
  report["scene"] = scene->name;
  if (args.cell_size <= 0) {
    ordered_json r;
    if (auto f = assemble_into(prims, options, out, r); !f.ok()) return f;
    for (auto& [k, v] : r.items()) report[k] = v;
    return {};
  }
  // Cells: the one asked for, or every cell holding a primitive's anchor.
  assembly::CellSpec grid;
  grid.grid.size = args.cell_size;
  grid.grid.halo = args.halo;
  std::vector<kernel::GridCell> cells;
  if (args.cell.size() == 2) {
    cells.push_back({args.cell[0], args.cell[1]});
  } else {
    std::set<kernel::GridCell> any;
    for (const auto& p : prims) {
      auto solid = kernel::build_primitive(p.spec, args.tolerance);
      if (!solid.ok()) continue;
      const kernel::BoundingBox b = kernel::bounding_box(solid.value());
      any.insert(grid.grid.cell_of(b.min.x(), b.min.y()));
    }
    cells.assign(any.begin(), any.end());
  }
  double volume = 0;
  ordered_json list = ordered_json::array();
  for (const kernel::GridCell& cell : cells) {
    grid.cell = cell;
    options.cell = grid;
    ordered_json r;
    const auto dir = out / ("cell_" + std::to_string(cell.column) + "_" + std::to_string(cell.row));
    if (auto f = assemble_into(prims, options, dir, r); !f.ok()) return f;
    volume += r["total_volume"].get<double>();
    list.push_back(std::move(r));
  }
  report["cell_size"] = args.cell_size;
  report["halo"] = args.halo;
  report["total_volume"] = volume;
  report["cells"] = std::move(list);
  return {};
}

void print_text(const ordered_json& r) {
  auto line = [](const ordered_json& c) {
    const auto& s = c["statistics"];
    std::printf(
        "%s: %lld objects (%lld failed, %lld past the halo) from %lld primitives; pairs: "
        "%lld candidates, %lld culled by OpenVDB, %lld tested exactly, %lld in contact; "
        "volume %.12g; %.3f s\n",
        c["model"].get<std::string>().c_str(), s["objects"].get<long long>(),
        s["objects_failed"].get<long long>(), s["objects_past_halo"].get<long long>(),
        s["primitives_read"].get<long long>(), s["candidate_pairs"].get<long long>(),
        s["culled_pairs"].get<long long>(), s["exact_tests"].get<long long>(),
        s["interacting_pairs"].get<long long>(), c["total_volume"].get<double>(),
        s["seconds"]["total"].get<double>());
    for (const auto& p : c["problems"])
      std::printf("  problem: %s\n", p.get<std::string>().c_str());
  };
  if (r.contains("cells")) {
    for (const auto& c : r["cells"]) line(c);
    std::printf("total volume %.12g\n", r["total_volume"].get<double>());
  } else {
    line(r);
  }
}

}  // namespace

void register_assemble(CLI::App& app, Action& action) {
  auto* cmd = app.add_subcommand(
      "assemble",
      "Assemble a scene's primitives into unified objects (OpenVDB culling, exact "
      "Booleans); write the city model and print the statistics and total volume");
  auto a = std::make_shared<AssembleArgs>();
  cmd->add_option("SCENE", a->scene, "Scene JSON file (scene format of shared/spec)")->required();
  cmd->add_option("--out", a->out, "Output directory (model.csgt, assembly.json)")->required();
  cmd->add_flag("--json", a->json, "Print one JSON object");
  cmd->add_option("--voxel", a->voxel, "OpenVDB voxel size, scene units (default 0.5)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--tolerance", a->tolerance, "Contact tolerance (default 1e-7)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--threads", a->threads, "Worker threads (default: all cores)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--snap-distance", a->snap_distance,
                  "Fuzzy mode for fitted primitives: plane faces this close become one plane "
                  "before the Booleans (kernel/snap.h; default 0: off)")
      ->check(CLI::Range(0.0, 1.0));
  cmd->add_option("--snap-angle", a->snap_degrees,
                  "Fuzzy mode: primitive axes within this angle (degrees) become one direction")
      ->check(CLI::Range(0.0, 10.0));
  cmd->add_option("--snap-escalate-to", a->escalate_to,
                  "Escalation: an object whose fuse fails is snapped again at 1, 2, 5, 10 ... "
                  "(scene units / 1000) up to this bound, until it fuses (default 0: off)")
      ->check(CLI::Range(0.0, 1.0));
  cmd->add_flag("--no-cull", a->no_cull,
                "Skip the OpenVDB culling (every candidate pair is tested exactly)");
  cmd->add_flag("--no-broad-phase", a->no_broad,
                "Skip the bounding-box broad phase (every pair is a candidate)");
  cmd->add_option("--cell-size", a->cell_size,
                  "Assemble per square cell of this size (grid at the origin)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--halo", a->halo, "Halo around each cell (with --cell-size)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--cell", a->cell, "Only this cell: I J (with --cell-size)")->expected(2);
  cmd->callback([&action, a] {
    action = [a] {
      ordered_json report;
      const Failure f = run_assemble(*a, report);
      if (!f.ok()) {
        if (a->json) {
          std::cout << ordered_json{{"error",
                                     std::string(error_info(f.code).name) + ": " + f.message}}
                           .dump()
                    << "\n";
        }
        std::fprintf(stderr, "csgtile assemble: %s\n", f.message.c_str());
        return error_info(f.code).exit_code;
      }
      if (a->json) {
        std::cout << report.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace) << "\n";
      } else {
        print_text(report);
      }
      return 0;
    };
  });
}

}  // namespace csgtile::worker::detail
