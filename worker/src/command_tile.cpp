// `csgtile tile INPUT.las --size S --out DIR [--json]`: cuts a LAS file into square tiles
// aligned to multiples of S in its CRS, as city runs take them (one fit job per tile). Each
// tile keeps the input's version, point format, scale, CRS records and extra bytes; its offset
// is the tile's minimum corner. Files are named <stem>_c<column>_r<row>.las and written
// through temporary files renamed at the end, so a failure leaves no partial tile. --out must
// be new or empty. One file is open per tile: a cut into more tiles than the process may
// open files (ulimit -n, often 1024) fails with an Io error naming the file.

#include <cmath>
#include <cstdio>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>

#include "commands.h"
#include "csgtile/geo/las.h"
#include "csgtile/kernel/grid.h"
#include "csgtile/worker/errors.h"
#include "csgtile/worker/files.h"
#include "fetch/fetch.h"

namespace csgtile::worker::detail {

namespace {

struct TileCommand {
  std::string input, out;
  double size = 0;
  bool json = false;
};

struct OpenTile {
  std::unique_ptr<geo::LasWriter> writer;
  std::filesystem::path temp, target;
  geo::PointBatch batch;
  bool committed = false;  ///< renamed onto target
};

int run_tile(const TileCommand& c) {
  nlohmann::ordered_json out{{"input", c.input}, {"size", c.size}};
  std::map<kernel::GridCell, OpenTile> tiles;
  auto fail = [&](const Failure& f) {
    for (auto& [id, t] : tiles) {
      t.writer.reset();
      std::error_code ec;
      std::filesystem::remove(t.committed ? t.target : t.temp, ec);
    }
    return detail::report_failure("tile", f, c.json, out);
  };
  if (!(c.size > 0) || !std::isfinite(c.size))
    return fail({ErrorCode::Usage, "--size must be > 0"});
  // A path, or a LAS/LAZ/COPC URL (http, https, s3) read by range requests.
  std::unique_ptr<geo::LasReader> opened;
  if (Failure f = fetch::open_las(c.input, fetch::Policy{}, opened); !f.ok()) {
    return fail(f);
  }
  geo::LasReader& reader = *opened;
  const geo::LasHeader& h = reader.header();
  std::error_code ec;
  // Tiles of an earlier cut (another size) beside the new ones would be read twice by a run
  // over the directory: the output directory must be new or empty.
  if (std::filesystem::exists(c.out, ec) && !std::filesystem::is_empty(c.out, ec)) {
    return fail({ErrorCode::Usage, c.out + ": not empty; tile into a new directory"});
  }
  std::filesystem::create_directories(c.out, ec);
  if (ec) return fail({ErrorCode::Io, c.out + ": " + ec.message()});
  const std::string stem = std::filesystem::path(c.input).stem().string();

  geo::LasWriteOptions options;
  options.version_minor = h.version_minor;
  options.point_format = h.point_format;
  options.scale = h.scale;
  const geo::LasCrsRecords& crs = reader.crs();
  if (crs.wkt) options.wkt = crs.wkt;
  if (crs.has_geotiff) options.geo_keys = crs.keys;
  options.global_encoding = h.global_encoding;

  const kernel::Grid grid{0.0, 0.0, c.size, 0.0};
  geo::PointBatch batch;
  std::uint64_t points = 0;
  for (;;) {
    auto n = reader.read(batch, 1 << 16);
    if (!n.ok()) return fail(failure_of(n.error()));
    if (n.value() == 0) break;
    for (std::size_t i = 0; i < batch.size(); ++i) {
      const geo::Point& p = batch.points[i];
      const kernel::GridCell id = grid.cell_of(p.x, p.y);
      auto it = tiles.find(id);
      if (it == tiles.end()) {
        OpenTile t;
        t.target = std::filesystem::path(c.out) / (stem + "_" + id.name() + ".las");
        t.temp = temp_path_beside(t.target, "tmp");
        geo::LasWriteOptions o = options;
        o.offset = {grid.edge_x(id.column), grid.edge_y(id.row), h.offset[2]};
        if (batch.layout) o.extra = *batch.layout;
        auto writer = geo::LasWriter::create(t.temp, o);
        if (!writer.ok()) return fail(failure_of(writer.error()));
        t.writer = std::move(writer).value();
        t.batch.layout = batch.layout;
        it = tiles.emplace(id, std::move(t)).first;
      }
      it->second.batch.append(p, batch.extra(i));
      ++points;
    }
    for (auto& [tid, t] : tiles) {
      if (t.batch.empty()) continue;
      if (auto st = t.writer->write(t.batch); !st.ok()) {
        return fail(failure_of(st.error(), t.target.string()));
      }
      t.batch.clear();
    }
  }
  nlohmann::ordered_json files = nlohmann::ordered_json::array();
  for (auto& [id, t] : tiles) {
    if (auto st = t.writer->close(); !st.ok()) {
      return fail(failure_of(st.error(), t.target.string()));
    }
    files.push_back({{"file", t.target.string()}, {"points", t.writer->points_written()}});
  }
  for (auto& [id, t] : tiles) {
    if (Failure f = commit_temp_file(t.temp, t.target); !f.ok()) return fail(f);
    t.committed = true;
  }
  out["points"] = points;
  out["tiles"] = files;
  out["error"] = nullptr;
  if (c.json) {
    std::cout << out.dump() << "\n";
  } else {
    for (const auto& f : files) {
      std::printf("%s  %llu points\n", f["file"].get<std::string>().c_str(),
                  static_cast<unsigned long long>(f["points"].get<std::uint64_t>()));
    }
  }
  return 0;
}

}  // namespace

void register_tile(CLI::App& app, Action& action) {
  auto* cmd = app.add_subcommand(
      "tile", "Cut a LAS file into square tiles aligned to multiples of --size in its CRS");
  auto c = std::make_shared<TileCommand>();
  cmd->add_option("INPUT", c->input, "LAS file")->required();
  cmd->add_option("--size", c->size, "Tile edge in CRS units")->required();
  cmd->add_option("--out", c->out, "Directory for <stem>_c<column>_r<row>.las")->required();
  cmd->add_flag("--json", c->json, "Print one JSON object");
  cmd->callback([&action, c] { action = [c] { return run_tile(*c); }; });
}

}  // namespace csgtile::worker::detail
