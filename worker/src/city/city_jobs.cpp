// The city run's job graph: keys, enqueueing, advancing and dispatch (see city_jobs.h).

#include "city/city_jobs.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string_view>

#include "city/city_internal.h"
#include "city/tile_share.h"
#include "csgtile/geo/las.h"
#include "csgtile/kernel/mass_properties.h"
#include "csgtile/kernel/native_format.h"
#include "csgtile/worker/files.h"
#include "csgtile/worker/publish.h"
#include "fetch/fetch.h"
#include "fetch/input.h"

namespace csgtile::worker::city {

namespace detail {

kernel::Grid run_grid(const config::Config& config) {
  return kernel::Grid{0.0, 0.0, config.city.cell_size, config.city.halo};
}

kernel::BoundingBox primitive_crs_box(const kernel::PrimitiveSpec& spec, const kernel::Vec3& origin,
                                      double tolerance) {
  auto solid = kernel::build_primitive(spec, tolerance);
  if (!solid.ok()) return {};
  kernel::BoundingBox box = kernel::bounding_box(solid.value());
  box.min += origin;
  box.max += origin;
  return box;
}

Failure ObjectBatch::add(const std::string& key, std::string bytes) {
  if (!is_safe_key(key)) return {ErrorCode::Internal, "unsafe object key " + key};
  if (!keys_.insert(key).second) return {};
  std::error_code ec;
  if (std::filesystem::exists(run_dir_ / key, ec)) return {};
  files_.emplace_back(run_dir_ / key, std::move(bytes));
  return {};
}

Failure ObjectBatch::commit() {
  Failure f = write_files_atomic(files_);
  files_.clear();
  return f;
}

Failure publish_object(const std::filesystem::path& run_dir, const std::string& key,
                       const std::string& bytes) {
  ObjectBatch batch(run_dir);
  if (Failure f = batch.add(key, bytes); !f.ok()) return f;
  return batch.commit();
}

Failure publish_model(const kernel::CsgModel& model, ObjectBatch& batch, PublishedModel& out) {
  return publish_native(kernel::write_native_model(model), batch, out);
}

Failure publish_native(std::string bytes, ObjectBatch& batch, PublishedModel& out) {
  out.sha256 = sha256_hex(bytes);
  out.key = "objects/" + out.sha256 + ".csgt";
  out.bytes = bytes.size();
  return batch.add(out.key, std::move(bytes));
}

std::string CellBlock::name() const { return first.name() + "-" + last.name(); }

std::array<std::int64_t, 4> CellBlock::corners() const {
  return {first.column, first.row, last.column, last.row};
}

std::array<double, 4> CellBlock::extent(const kernel::Grid& grid) const {
  return {grid.edge_x(first.column), grid.edge_y(first.row), grid.edge_x(last.column + 1),
          grid.edge_y(last.row + 1)};
}

std::optional<CellBlock> CellBlock::parse(const nlohmann::json& corners) {
  if (!corners.is_array() || corners.size() != 4 ||
      !std::all_of(corners.begin(), corners.end(),
                   [](const nlohmann::json& v) { return v.is_number_integer(); })) {
    return std::nullopt;
  }
  const CellBlock b{{corners[0].get<std::int64_t>(), corners[1].get<std::int64_t>()},
                    {corners[2].get<std::int64_t>(), corners[3].get<std::int64_t>()}};
  if (b.first.column > b.last.column || b.first.row > b.last.row) return std::nullopt;
  return b;
}

Failure describe_file(const std::filesystem::path& dir, const std::string& key, ordered_json& out) {
  std::string bytes;
  if (Failure f = read_file_bytes(dir / key, bytes); !f.ok()) return f;
  out = {{"key", key}, {"sha256", sha256_hex(bytes)}, {"bytes", bytes.size()}};
  return {};
}

std::vector<std::pair<std::string, ordered_json>> done_records(
    const std::vector<std::pair<std::string, std::string>>& results, const std::string& kind,
    const std::string& run) {
  const std::string prefix = kind + ":" + run + ":";
  std::vector<std::pair<std::string, ordered_json>> out;
  for (const auto& [key, text] : results) {
    if (key.compare(0, prefix.size(), prefix) != 0) continue;
    ordered_json record = ordered_json::parse(text, nullptr, false);
    if (record.is_discarded()) continue;
    out.emplace_back(key, std::move(record));
  }
  return out;
}

}  // namespace detail

using detail::ordered_json;

namespace {
bool is_local_directory(const std::string& input) {
  if (input.find("://") != std::string::npos) return false;
  std::error_code ec;
  return std::filesystem::is_directory(input, ec);
}
}  // namespace

bool is_tile_input(const std::string& input) {
  if (is_local_directory(input)) return true;
  std::string path = input.substr(0, input.find_first_of("?#"));
  const std::size_t dot = path.rfind('.');
  if (dot == std::string::npos || path.find('/', dot) != std::string::npos) return false;
  std::string ext = path.substr(dot + 1);
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext == "las" || ext == "laz" || ext == "ply" || ext == "pcd" || ext == "xyz" ||
         ext == "txt";
}

std::string fit_key(const std::string& run, const std::string& input) {
  return "fit:" + run + ":" + input;
}
std::string assemble_key(const std::string& run, const std::string& cell) {
  return "assemble:" + run + ":" + cell;
}
std::string index_key(const std::string& run) { return "index:" + run + ":run"; }

namespace {

using detail::CellBlock;

/// One fit job's tile: an input file; one cell of a COPC input (`cell` set: the job reads
/// the octree nodes meeting the cell grown by city.halo and shares the buildings across its
/// edges with the neighbouring cells, tile_share.h); or one block of cells of a LAS/LAZ input
/// of more than city.split_points points (`block` set: the job streams the file and keeps the
/// block grown by the halo, sharing as a cell does). `id` names it in queue keys and labels:
/// the input, with " @<cell>" or " @<first cell>-<last cell>".
struct Tile {
  std::string id;
  std::string input;
  std::optional<kernel::GridCell> cell;
  std::size_t index = 0;
  /// Of a LAS/LAZ tile in a run of several: its header's xy bounds (its fit reads the points
  /// of the tiles around it, tile_share.h); of a block, the block's cells' square.
  std::optional<Extent> extent = {};
  std::optional<CellBlock> block = {};
};

// Whether the input's path (its query and fragment aside) ends, in any case, with `suffix`
// after at least one character.
bool name_ends_with(const std::string& input, std::string_view suffix) {
  std::string path = input.substr(0, input.find_first_of("?#"));
  for (char& c : path) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return path.size() > suffix.size() &&
         path.compare(path.size() - suffix.size(), suffix.size(), suffix) == 0;
}

bool is_las_name(const std::string& input) {
  return name_ends_with(input, ".las") || name_ends_with(input, ".laz");
}

bool is_copc_name(const std::string& input) { return name_ends_with(input, ".copc.laz"); }

// The cells of the run's grid between the xy bounds of a header; fails past 10^6 cells.
Failure cells_between(const std::string& input, const kernel::Grid& grid, const geo::LasHeader& h,
                      kernel::GridCell& low, kernel::GridCell& high, bool& empty) {
  empty = !(h.min[0] <= h.max[0]) || !(h.min[1] <= h.max[1]);  // no points
  if (empty) return {};
  low = grid.cell_of(h.min[0], h.min[1]);
  high = grid.cell_of(h.max[0], h.max[1]);
  const double count = static_cast<double>(high.column - low.column + 1) *
                       static_cast<double>(high.row - low.row + 1);
  if (count > 1e6) {
    return {ErrorCode::InputInvalid, input + ": its extent covers " + std::to_string(count) +
                                         " cells of city.cell_size (more than 10^6)"};
  }
  return {};
}

// The blocks of cells a LAS/LAZ input is fitted in (city.split_points): square blocks of as
// many cells as hold about split_points points at the density its header declares (its
// readable points over the area of its bounds, a side shorter than a cell counted as a
// cell), from the first cell of its bounds; a block is one cell at least. Empty (one fit job
// for the file) when it declares no more points than that, when one block would cover it,
// when its bounds cover more than 10^6 cells, or when its header cannot be read locally (its
// fit job then fails with the reader's reason); a URL whose header cannot be fetched in
// transit fails the enqueue (Network), so that a run's tiles never depend on a passing failure.
Failure split_blocks(const std::string& input, const config::Config& config,
                     std::vector<CellBlock>& blocks, std::optional<Extent>& bounds) {
  blocks.clear();
  bounds.reset();
  if (config.city.split_points == 0 || !is_las_name(input) || is_copc_name(input)) return {};
  std::unique_ptr<geo::LasReader> reader;
  if (Failure f = fetch::open_las(input, fetch::policy_of(config.fetch), reader); !f.ok()) {
    return f.code == ErrorCode::Network ? f : Failure{};
  }
  const geo::LasHeader& h = reader->header();
  if (h.min[0] <= h.max[0] && h.min[1] <= h.max[1]) {
    bounds = Extent{h.min[0], h.min[1], h.max[0], h.max[1]};
  }
  // The records the file holds (a header is not trusted past them).
  const std::uint64_t points = reader->readable_points();
  if (points <= config.city.split_points) return {};
  kernel::GridCell low, high;
  bool empty = false;
  if (!cells_between(input, detail::run_grid(config), h, low, high, empty).ok() || empty) {
    return {};
  }
  const std::int64_t columns = high.column - low.column + 1;
  const std::int64_t rows = high.row - low.row + 1;
  const double cell = config.city.cell_size;
  const double area = std::max(h.max[0] - h.min[0], cell) * std::max(h.max[1] - h.min[1], cell);
  const double per_cell = static_cast<double>(points) * cell * cell / area;
  const auto side = std::max<std::int64_t>(
      1, static_cast<std::int64_t>(
             std::floor(std::sqrt(static_cast<double>(config.city.split_points) / per_cell))));
  if (side >= columns && side >= rows) return {};
  for (std::int64_t c = low.column; c <= high.column; c += side) {
    for (std::int64_t r = low.row; r <= high.row; r += side) {
      blocks.push_back(
          {{c, r}, {std::min(c + side - 1, high.column), std::min(r + side - 1, high.row)}});
    }
  }
  return {};
}

// The cells a COPC input's header bounds cover (its header read locally, or by range
// requests for a URL). Errors: as the readers and the fetcher.
Failure copc_cells(const std::string& input, const config::Config& config,
                   std::vector<kernel::GridCell>& cells) {
  cells.clear();
  std::unique_ptr<geo::LasReader> reader;
  if (Failure f = fetch::open_las(input, fetch::policy_of(config.fetch), reader); !f.ok()) {
    return f;
  }
  kernel::GridCell low, high;
  bool empty = false;
  if (Failure f =
          cells_between(input, detail::run_grid(config), reader->header(), low, high, empty);
      !f.ok() || empty) {
    return f;
  }
  for (std::int64_t c = low.column; c <= high.column; ++c) {
    for (std::int64_t r = low.row; r <= high.row; ++r) cells.push_back({c, r});
  }
  return {};
}

/// Distinct tile inputs of the run, each with its position (the tile's number in labels): a
/// local directory stands for the tile files directly inside it, in name order; an input
/// named *.copc.laz stands for one tile per cell of city.cell_size its extent covers.
Failure expand_tile_inputs(const config::Config& config, std::vector<Tile>& out) {
  std::vector<std::string> expanded;
  for (const std::string& input : config.run.inputs) {
    if (!is_local_directory(input)) {
      expanded.push_back(input);
      continue;
    }
    std::vector<std::string> files;
    std::error_code ec;
    std::filesystem::directory_iterator it(input, ec), end;
    for (; !ec && it != end; it.increment(ec)) {
      const std::string name = it->path().filename().string();
      std::error_code type_ec;
      if (it->is_regular_file(type_ec) && name[0] != '.' && is_tile_input(name)) {
        files.push_back((std::filesystem::path(input) / name).lexically_normal().string());
      }
    }
    std::sort(files.begin(), files.end());
    expanded.insert(expanded.end(), files.begin(), files.end());
  }
  out.clear();
  std::set<std::string> seen;
  std::map<std::string, Extent> header_bounds;
  for (const std::string& input : expanded) {
    if (!is_tile_input(input) || !seen.insert(input).second) continue;
    if (!is_copc_name(input)) {
      std::vector<CellBlock> blocks;
      std::optional<Extent> bounds;
      if (Failure f = split_blocks(input, config, blocks, bounds); !f.ok()) return f;
      if (bounds) header_bounds[input] = *bounds;  // read once
      if (blocks.empty()) out.push_back({input, input, std::nullopt, out.size()});
      const kernel::Grid grid = detail::run_grid(config);
      for (const CellBlock& b : blocks) {
        out.push_back(
            {input + " @" + b.name(), input, std::nullopt, out.size(), b.extent(grid), b});
      }
      continue;
    }
    std::vector<kernel::GridCell> cells;
    if (Failure f = copc_cells(input, config, cells); !f.ok()) return f;
    for (const kernel::GridCell& cell : cells) {
      out.push_back({input + " @" + cell.name(), input, cell, out.size()});
    }
  }
  // Several LAS/LAZ tiles (blocks of a split input among them): each one's extent from its
  // header, so that each fit reads its neighbours' points near its edges. A header that cannot be
  // read leaves its tile without (its fit job fails with the reader's reason).
  const auto plain = std::count_if(out.begin(), out.end(),
                                   [](const Tile& t) { return !t.cell && is_las_name(t.input); });
  if (plain < 2) return {};
  for (Tile& t : out) {
    if (t.cell || t.block || !is_las_name(t.input)) continue;
    if (const auto it = header_bounds.find(t.input); it != header_bounds.end()) {
      t.extent = it->second;
      continue;
    }
    std::unique_ptr<geo::LasReader> reader;
    if (!fetch::open_las(t.input, fetch::policy_of(config.fetch), reader).ok()) continue;
    const geo::LasHeader& h = reader->header();
    if (h.min[0] <= h.max[0] && h.min[1] <= h.max[1]) {
      t.extent = Extent{h.min[0], h.min[1], h.max[0], h.max[1]};
    }
  }
  return {};
}

std::filesystem::path tiles_file(const config::Config& config) {
  return std::filesystem::path(config.run.output) / "runs" / config.run.name / "tiles.json";
}

/// The run's tiles as fixed when it was first enqueued (<run dir>/tiles.json: an input
/// string; {"input", "extent": [xmin, ymin, xmax, ymax]} for a LAS/LAZ tile among several;
/// {"input", "cell": [column, row]} for a cell of a COPC input; {"input", "block": [first
/// column, first row, last column, last row]} for a block of a tile over city.split_points),
/// so that tiles added to an input directory later do not change a run under way; before
/// that, the inputs expanded now. Error: Internal naming an entry it does not read (a run
/// must never go on without some of its tiles).
Failure tile_inputs(const config::Config& config, std::vector<Tile>& out) {
  std::string text;
  out.clear();
  if (!read_file_bytes(tiles_file(config), text).ok()) {
    if (!expand_tile_inputs(config, out).ok()) out.clear();
    return {};
  }
  const auto doc = nlohmann::json::parse(text, nullptr, false);
  const std::string file = tiles_file(config).string();
  if (!doc.is_object() || !doc.contains("tiles") || !doc["tiles"].is_array()) {
    return {ErrorCode::Internal, file + " is not a list of tiles"};
  }
  auto integers = [](const nlohmann::json& v, std::size_t n) {
    return v.is_array() && v.size() == n &&
           std::all_of(v.begin(), v.end(),
                       [](const nlohmann::json& x) { return x.is_number_integer(); });
  };
  const kernel::Grid grid = detail::run_grid(config);
  for (const auto& t : doc["tiles"]) {
    if (t.is_string()) {
      out.push_back({t.get<std::string>(), t.get<std::string>(), std::nullopt, out.size()});
      continue;
    }
    const bool has_input = t.is_object() && t.contains("input") && t["input"].is_string();
    const std::string input = has_input ? t["input"].get<std::string>() : std::string();
    if (has_input && t.contains("extent") && t["extent"].is_array() && t["extent"].size() == 4 &&
        std::all_of(t["extent"].begin(), t["extent"].end(),
                    [](const nlohmann::json& x) { return x.is_number(); })) {
      Extent e{};
      for (std::size_t k = 0; k < 4; ++k) e[k] = t["extent"][k].get<double>();
      out.push_back({input, input, std::nullopt, out.size(), e});
    } else if (const auto b =
                   has_input && t.contains("block") ? CellBlock::parse(t["block"]) : std::nullopt) {
      out.push_back(
          {input + " @" + b->name(), input, std::nullopt, out.size(), b->extent(grid), *b});
    } else if (has_input && t.contains("cell") && integers(t["cell"], 2)) {
      const kernel::GridCell cell{t["cell"][0].get<std::int64_t>(),
                                  t["cell"][1].get<std::int64_t>()};
      out.push_back({input + " @" + cell.name(), input, cell, out.size()});
    } else {
      out.clear();
      return {ErrorCode::Internal, file + ": tile entry " + t.dump() + " is not one it reads"};
    }
  }
  return {};
}

}  // namespace

Failure enqueue_fits(const config::Config& config, JobQueue& queue, std::size_t& added) {
  added = 0;
  Failure failure;
  std::error_code ec;
  if (!std::filesystem::exists(tiles_file(config), ec)) {
    // The first enqueue fixes the run's tile list.
    std::vector<Tile> expanded;
    if (Failure f = expand_tile_inputs(config, expanded); !f.ok()) return f;
    nlohmann::ordered_json doc = {{"run", config.run.name},
                                  {"tiles", nlohmann::ordered_json::array()}};
    for (const Tile& t : expanded) {
      if (t.cell) {
        doc["tiles"].push_back({{"input", t.input}, {"cell", {t.cell->column, t.cell->row}}});
      } else if (t.block) {
        doc["tiles"].push_back({{"input", t.input}, {"block", t.block->corners()}});
      } else if (t.extent) {
        doc["tiles"].push_back({{"input", t.input}, {"extent", *t.extent}});
      } else {
        doc["tiles"].push_back(t.input);
      }
    }
    if (Failure f = write_file_atomic(tiles_file(config), doc.dump(2) + "\n"); !f.ok()) return f;
  }
  // Each LAS/LAZ tile's neighbours: the tiles that can own a building it sees.
  std::vector<Tile> tiles;
  if (Failure f = tile_inputs(config, tiles); !f.ok()) return f;
  // A cell of a COPC input: the cell's square.
  const kernel::Grid grid = detail::run_grid(config);
  auto extent_of = [&grid](const Tile& t) -> std::optional<Extent> {
    if (!t.cell) return t.extent;
    return CellBlock{*t.cell, *t.cell}.extent(grid);
  };
  std::vector<TileExtent> extents;
  std::vector<std::size_t> of_tile(tiles.size(), SIZE_MAX);
  for (const Tile& t : tiles) {
    const auto e = extent_of(t);
    if (!e) continue;
    of_tile[t.index] = extents.size();
    extents.push_back({t.index, t.input, *e});
  }
  const auto near = neighbours_of(extents, 2.0 * config.city.halo);
  for (const Tile& t : tiles) {
    nlohmann::json payload = {{"input", t.input}, {"tile", t.index}};
    if (t.cell) payload["cell"] = {t.cell->column, t.cell->row};
    if (t.block) payload["block"] = t.block->corners();
    if (of_tile[t.index] != SIZE_MAX) {
      payload["extent"] = extents[of_tile[t.index]].extent;
      payload["neighbours"] = nlohmann::json::array();
      for (std::size_t k : near[of_tile[t.index]]) {
        const TileExtent& n = extents[k];
        payload["neighbours"].push_back(
            {{"input", n.input}, {"tile", n.tile}, {"extent", n.extent}});
      }
    }
    if (queue.enqueue(fit_key(config.run.name, t.id), "fit", payload.dump(), failure)) ++added;
    if (!failure.ok()) return failure;
  }
  return failure;
}

namespace {
Failure advance(const config::Config& config, JobQueue& queue, const Logger& log,
                std::size_t& enqueued) {
  enqueued = 0;
  const std::string& run = config.run.name;
  Failure failure;
  // A stage follows when nothing is unfinished: a cheap count first, so that the records
  // are read once per stage, not after every job.
  const QueueCounts counts = queue.counts(failure);
  if (!failure.ok()) return failure;
  if (counts.unfinished() > 0) return {};
  std::vector<Tile> tiles;
  if (Failure f = tile_inputs(config, tiles); !f.ok()) return f;
  if (tiles.empty()) return {};
  const auto results = queue.results(failure);
  if (!failure.ok()) return failure;
  std::set<std::string> dead;
  for (const DeadJob& d : queue.dead_jobs(failure)) dead.insert(d.key);
  if (!failure.ok()) return failure;

  std::set<std::string> done;
  for (const auto& r : results) done.insert(r.first);
  std::map<std::string, ordered_json> fits;
  for (auto& [key, record] : detail::done_records(results, "fit", run))
    fits[key] = std::move(record);
  std::size_t finished = 0;
  for (const Tile& t : tiles) {
    const std::string key = fit_key(run, t.id);
    if (fits.count(key) || dead.count(key)) ++finished;
  }
  if (finished < tiles.size()) return {};  // fits still running

  // The run's CRS is the first done tile's (in run.inputs order); tiles in another CRS are
  // left out of every cell (the index job names them).
  std::optional<std::string> crs;
  std::map<std::string, std::vector<ordered_json>> cell_fits;  // cell name → fits meeting its halo
  std::map<std::string, kernel::GridCell> cells;
  const kernel::Grid grid = detail::run_grid(config);
  for (const Tile& t : tiles) {
    const auto it = fits.find(fit_key(run, t.id));
    if (it == fits.end()) continue;
    const ordered_json& record = it->second;
    const std::string tile_crs = record.value("crs", "");
    if (!crs) crs = tile_crs;
    if (tile_crs != *crs) continue;
    for (const auto& name : record.at("anchor_cells")) {
      const auto& c = name;
      cells.emplace(
          c.at("name").get<std::string>(),
          kernel::GridCell{c.at("column").get<std::int64_t>(), c.at("row").get<std::int64_t>()});
    }
  }
  for (const auto& [name, cell] : cells) {
    std::vector<ordered_json> near;
    for (const Tile& t : tiles) {
      const auto it = fits.find(fit_key(run, t.id));
      if (it == fits.end() || it->second.value("crs", "") != *crs) continue;
      const ordered_json& b = it->second.at("bounds");
      if (b.is_null()) continue;
      kernel::BoundingBox box;
      box.add(kernel::Vec3(b.at(0).get<double>(), b.at(1).get<double>(), b.at(2).get<double>()));
      box.add(kernel::Vec3(b.at(3).get<double>(), b.at(4).get<double>(), b.at(5).get<double>()));
      if (!grid.meets_halo(box, cell)) continue;
      ordered_json fit = {{"fit", it->first},
                          {"tile", t.index},
                          {"scene", it->second.at("scene")},
                          {"origin", it->second.at("origin")}};
      // The points its objects are measured against (model_fit.h), when the fit kept them.
      if (it->second.contains("structure_points")) {
        fit["structure_points"] = it->second.at("structure_points");
      }
      near.push_back(std::move(fit));
    }
    cell_fits[name] = std::move(near);
  }
  std::size_t assembled = 0;
  for (const auto& [name, cell] : cells) {
    const std::string key = assemble_key(run, name);
    const ordered_json payload = {{"cell", name},
                                  {"column", cell.column},
                                  {"row", cell.row},
                                  {"crs", *crs},
                                  {"fits", cell_fits[name]}};
    if (queue.enqueue(key, "assemble", payload.dump(), failure)) ++enqueued;
    if (!failure.ok()) return failure;
    if (dead.count(key) || done.count(key)) ++assembled;
  }
  if (enqueued > 0) {
    log.info("run", "fits finished; cells enqueued",
             {{"run", run}, {"cells", std::to_string(cells.size())}});
  }
  if (assembled < cells.size()) return {};
  if (queue.enqueue(index_key(run), "index",
                    ordered_json({{"cells", cells.size()}, {"crs", crs.value_or("")}}).dump(),
                    failure)) {
    ++enqueued;
    log.info("run", "cells finished; index enqueued", {{"run", run}});
  }
  return failure;
}

}  // namespace

// Records and payloads are our own JSON; one that does not parse as expected is a bug or a
// foreign writer, reported as an Internal failure rather than an exception that would end
// the worker.
Failure advance_city_run(const config::Config& config, JobQueue& queue, const Logger& log,
                         std::size_t& enqueued) {
  try {
    return advance(config, queue, log, enqueued);
  } catch (const nlohmann::json::exception& e) {
    return {ErrorCode::Internal,
            "run " + config.run.name + ": a fit record is malformed: " + e.what()};
  } catch (const std::exception& e) {
    return {ErrorCode::Internal, "run " + config.run.name + ": " + e.what()};
  }
}

Failure city_progress(const config::Config& config, JobQueue& queue, CityProgress& progress) {
  progress = CityProgress{};
  const std::string& run = config.run.name;
  std::vector<Tile> tiles;
  if (Failure f = tile_inputs(config, tiles); !f.ok()) return f;
  progress.tiles = tiles.size();
  Failure failure;
  const auto results = queue.results(failure);
  if (!failure.ok()) return failure;
  const auto dead = queue.dead_jobs(failure);
  if (!failure.ok()) return failure;
  auto has_prefix = [](const std::string& key, const std::string& prefix) {
    return key.compare(0, prefix.size(), prefix) == 0;
  };
  const std::string fit = "fit:" + run + ":", cell = "assemble:" + run + ":";
  for (const auto& [key, text] : results) {
    if (has_prefix(key, fit)) ++progress.fits_done;
    if (has_prefix(key, cell)) ++progress.cells_done;
    if (key == index_key(run)) progress.indexed = true;
  }
  for (const DeadJob& d : dead) {
    if (has_prefix(d.key, fit)) ++progress.fits_dead;
    if (has_prefix(d.key, cell)) ++progress.cells_dead;
    if (d.key == index_key(run)) progress.index_dead = true;
  }
  if (progress.fits_done + progress.fits_dead >= progress.tiles) {
    std::set<std::string> cells;
    try {
      for (const auto& [key, record] : detail::done_records(results, "fit", run)) {
        for (const auto& c : record.at("anchor_cells"))
          cells.insert(c.at("name").get<std::string>());
      }
    } catch (const nlohmann::json::exception& e) {
      return {ErrorCode::Internal, "run " + run + ": a fit record is malformed: " + e.what()};
    }
    progress.cells = cells.size();
  }
  return {};
}

namespace {
// A malformed payload or record, or a file system error, ends the job with its reason.
template <typename Body>
Failure guarded(const Job& job, Body body) {
  try {
    return body();
  } catch (const nlohmann::json::exception& e) {
    return {ErrorCode::Internal,
            "job " + job.key + ": a payload or record is malformed: " + e.what()};
  } catch (const std::filesystem::filesystem_error& e) {
    return {ErrorCode::Io, "job " + job.key + ": " + e.what()};
  }
}
}  // namespace

Failure run_fit(const Job& job, const jobs::JobContext& c, std::string& result,
                StageTimings* timings) {
  return guarded(
      job, [&] { return detail::run_fit_job(job, c.run_dir, c.config, result, timings, c.stop); });
}

Failure run_assemble(const Job& job, const jobs::JobContext& c, std::string& result,
                     StageTimings* timings) {
  return guarded(job, [&] {
    return detail::run_assemble_job(job, c.run_dir, c.config, result, timings, c.stop);
  });
}

Failure run_index(const Job& job, const jobs::JobContext& c, std::string& result,
                  StageTimings* timings) {
  return guarded(job, [&] {
    return detail::run_index_job(job, c.run_dir, c.config, c.queue, c.log, result, timings);
  });
}

}  // namespace csgtile::worker::city
