// The `fit` job of a city run: one LIDAR tile → its fitted primitives, published as a scene
// file in the tile's frame, with the cells holding their anchors (city_jobs.h).

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <optional>
#include <set>

#include "city/city_internal.h"
#include "city/fit_tile.h"
#include "city/model_fit.h"
#include "csgtile/geo/scene.h"
#include "csgtile/kernel/check.h"
#include "csgtile/kernel/mass_properties.h"
#include "csgtile/kernel/primitives.h"
#include "csgtile/worker/publish.h"
#include "fetch/fetch.h"
#include "fetch/input.h"
#include "ops/metrics.h"
#include "ops/stage_clock.h"

namespace csgtile::worker::city::detail {

Failure run_fit_job(const Job& job, const std::filesystem::path& run_dir,
                    const config::Config& config, std::string& result, StageTimings* timings,
                    std::stop_token stop) {
  ops::StageClock clock(timings);
  std::shared_ptr<fetch::RangeStats> range_stats;  // a COPC cell read by range requests
  clock.enter("fetch");
  std::string input;
  fetch::LocalInput local;
  const auto payload = nlohmann::json::parse(job.payload, nullptr, false);
  if (payload.is_discarded() || !payload.is_object() || !payload.contains("input") ||
      !payload["input"].is_string()) {
    return {ErrorCode::Internal, "job " + job.key + " has a malformed payload"};
  }
  // A cell of a COPC input: only the octree nodes meeting the cell and its halo are read
  // (by range requests for a URL: no download of the file); the buildings across its edges
  // are shared with the neighbouring cells (tile_share.h).
  std::optional<kernel::GridCell> only_cell;
  TileSource source;
  if (payload.contains("cell")) {
    const auto& c = payload["cell"];
    if (!c.is_array() || c.size() != 2 || !c[0].is_number_integer() || !c[1].is_number_integer()) {
      return {ErrorCode::Internal, "job " + job.key + " has a malformed cell"};
    }
    only_cell = kernel::GridCell{c[0].get<std::int64_t>(), c[1].get<std::int64_t>()};
    const kernel::BoundingBox halo = run_grid(config).halo_box(*only_cell);
    geo::Bounds3 region;
    region.min = {halo.min.x(), halo.min.y(), halo.min.z()};
    region.max = {halo.max.x(), halo.max.y(), halo.max.z()};
    source.region = region;
    input = payload["input"].get<std::string>();
    if (fetch::is_remote_url(input)) {
      auto stats = std::make_shared<fetch::RangeStats>();
      if (Failure f =
              fetch::open_range_source(input, fetch::policy_of(config.fetch), source.remote, stats);
          !f.ok()) {
        return f;
      }
      range_stats = stats;
      local.path = input;
      local.fetched = true;
    }
  }
  // A block of cells of a large LAS/LAZ input (city.split_points): the job streams the file
  // and keeps the block grown by the halo, sharing the buildings across its edges as a COPC
  // cell does.
  std::optional<std::string> block_name;
  if (payload.contains("block")) {
    const auto block = CellBlock::parse(payload["block"]);
    if (!block || !payload.contains("extent") || !payload.contains("neighbours")) {
      return {ErrorCode::Internal, "job " + job.key + " has a malformed block"};
    }
    block_name = block->name();
  }
  if (!source.remote) {
    if (Failure f = fetch::resolve_job_input(job, config, input, local); !f.ok()) return f;
    source.path = local.path;
  }

  // A LAS/LAZ tile among others: the tiles around it, and the local files of those whose
  // points its fit reads (tile_share.h).
  std::optional<TileNeighbours> around;
  if (payload.contains("extent") && payload.contains("neighbours")) {
    auto extent_of = [](const nlohmann::json& e) {
      Extent out{};
      for (std::size_t k = 0; k < 4; ++k) out[k] = e.at(k).get<double>();
      return out;
    };
    around.emplace();
    around->where.self = {payload.value("tile", std::size_t{0}), input,
                          extent_of(payload["extent"])};
    around->where.halo = config.city.halo;
    // A COPC cell's or a block's read holds its halo: the neighbouring cells' points come
    // with it.
    around->own_read_is_shared = only_cell.has_value() || block_name.has_value();
    const Extent region = around->where.read_region();
    if (block_name) {
      source.region =
          geo::Bounds3{{region[0], region[1], -INFINITY}, {region[2], region[3], INFINITY}};
    }
    std::set<std::string> read_inputs;
    for (const auto& n : payload["neighbours"]) {
      TileExtent t{n.at("tile").get<std::size_t>(), n.at("input").get<std::string>(),
                   extent_of(n.at("extent"))};
      std::filesystem::path path;
      // Each input read once (the cells of a COPC input share it; this tile's own is read).
      if (t.input != input && !read_inputs.count(t.input) && extents_meet(t.extent, region)) {
        read_inputs.insert(t.input);
        fetch::LocalInput near;
        // A failure in transit is retried (the job's result must not depend on it).
        if (Failure f = fetch::resolve_input(t.input, config, near); !f.ok()) {
          if (f.code == ErrorCode::Network) return f;
          around->skipped.push_back(t.input + ": " + f.message);
        } else {
          path = near.path;
        }
      }
      around->where.neighbours.push_back(std::move(t));
      around->paths.push_back(std::move(path));
    }
  }

  clock.enter("fit");
  fit::FitPipelineOptions options = fit_options(config);
  options.interrupt.stop = std::move(stop);
  options.keep_structure_points = true;  // published for the cells' model fit (model_fit.h)
  FittedTile tile;
  std::string name =
      std::filesystem::path(input.substr(0, input.find_first_of("?#"))).stem().string();
  if (only_cell) name += "_" + only_cell->name();
  if (block_name) name += "_" + *block_name;
  const geo::FootprintSource footprints{config.city.footprints, config.city.footprints_layer,
                                        config.city.footprints_id};
  if (Failure f = fit_tile(std::move(source), name, options, config.run.crs, tile, footprints,
                           around ? &*around : nullptr);
      !f.ok()) {
    // A range read that failed in transit keeps its own code (Network: the job is retried).
    if (range_stats && !range_stats->last_failure.ok()) return range_stats->last_failure;
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
    } else if (const kernel::CheckReport check = kernel::check_shape(solid.value());
               !check.valid()) {
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
  std::string text = geo::scene_to_json(tile.scene);
  // Anchors from the file as the assemble jobs will read it (primitive_crs_box): the same
  // bytes through the same code, so every job puts a primitive in the same cell.
  auto published = geo::parse_scene(text);
  if (!published.ok()) return {ErrorCode::Internal, input + ": " + published.error().message};
  kernel::BoundingBox bounds;
  std::map<std::string, kernel::GridCell> anchors;
  const kernel::Grid grid = run_grid(config);
  std::size_t other_cells = 0;
  std::vector<geo::ScenePrimitive> in_cell;
  for (const geo::ScenePrimitive& p : published->primitives) {
    const kernel::BoundingBox box = primitive_crs_box(p.spec, o, config.kernel.linear_tolerance);
    if (box.empty())
      return {ErrorCode::Internal, input + ": primitive " + p.id + " does not rebuild"};
    const kernel::GridCell cell = grid.cell_of(box.min.x(), box.min.y());
    // Among neighbours the tile share decided which buildings are this fit's; a cell
    // without (a run enqueued before) keeps the primitives anchored in it.
    if (only_cell && !around && cell != *only_cell) {
      ++other_cells;  // anchored in a neighbour cell: that cell's job keeps it
      continue;
    }
    bounds.add(box);
    anchors.emplace(cell.name(), cell);
    in_cell.push_back(p);
  }
  if (other_cells > 0) {
    geo::Scene kept_scene = published.value();
    kept_scene.primitives = std::move(in_cell);
    tile.scene.primitives = kept_scene.primitives;
    text = geo::scene_to_json(kept_scene);
  }
  const std::string sha = sha256_hex(text);
  const std::string key = "fits/" + sha + ".json";
  if (Failure f = publish_object(run_dir, key, text); !f.ok()) return f;

  ordered_json record;
  record["input"] = input;
  record["input_sha256"] = local.sha256;
  record["tile"] = payload.value("tile", 0);
  if (only_cell) {
    record["cell"] = only_cell->name();
    if (!around) record["primitives_of_other_cells"] = other_cells;
  }
  if (block_name) record["block"] = *block_name;
  if (range_stats) {
    record["range_reads"] = {{"requests", range_stats->requests}, {"bytes", range_stats->bytes}};
    ops::metrics().add_bytes_fetched(range_stats->bytes);
  }
  record["scene"] = {{"key", key}, {"sha256", sha}, {"bytes", text.size()}};
  // The points the model is to explain, in the tile frame: each cell measures its objects'
  // distances to them.
  if (!fit.structure_points.empty()) {
    const std::string points = encode_points(fit.structure_points);
    const std::string points_sha = sha256_hex(points);
    const std::string points_key = "points/" + points_sha + ".pts";
    if (Failure f = publish_object(run_dir, points_key, points); !f.ok()) return f;
    record["structure_points"] = {{"key", points_key},
                                  {"sha256", points_sha},
                                  {"bytes", points.size()},
                                  {"count", fit.structure_points.size()}};
  }
  record["crs"] = tile.scene.frame ? tile.scene.frame->crs : std::string();
  record["origin"] = origin;
  record["seed"] = options.ransac.seed;
  // The fit section as the canonical config JSON writes it: same options, same hash.
  record["fit_options_sha256"] = sha256_hex(config::to_json(config.fit));
  record.update(fit_counts_json(fit));
  if (!footprints.source.empty()) record["footprints"] = footprints_record(footprints, tile);
  if (around) record["neighbours"] = neighbours_record(tile);
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
  record["bounds"] = bounds.empty()
                         ? ordered_json()
                         : ordered_json::array({bounds.min.x(), bounds.min.y(), bounds.min.z(),
                                                bounds.max.x(), bounds.max.y(), bounds.max.z()});
  ordered_json cells = ordered_json::array();
  for (const auto& [cell_name, cell] : anchors) {
    cells.push_back({{"name", cell_name}, {"column", cell.column}, {"row", cell.row}});
  }
  record["anchor_cells"] = cells;
  result = record.dump();
  return {};
}

}  // namespace csgtile::worker::city::detail
