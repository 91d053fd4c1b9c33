// One tile's points → fitted primitives (see fit_tile.h).

#include "city/fit_tile.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <optional>
#include <span>

#include "csgtile/geo/crs.h"
#include "csgtile/geo/las.h"
#include "csgtile/geo/point_reader.h"
#include "csgtile/geo/scene_units.h"

namespace csgtile::worker::city {

nlohmann::ordered_json fit_counts_json(const fit::FitOutput& f) {
  return {{"points", f.input_points},
          {"ground_points", f.ground_points},
          {"other_class_points", f.other_class_points},
          {"outlier_points", f.outlier_points},
          {"vegetation_points", f.vegetation_points},
          {"fitted_points", f.fitted_points},
          {"small_cluster_points", f.small_cluster_points},
          {"assigned_points", f.assigned_points},
          {"unassigned_points", f.unassigned_points},
          {"regions", f.regions}};
}

nlohmann::ordered_json neighbours_record(const FittedTile& tile) {
  return {{"read", tile.neighbours_read},
          {"skipped", tile.neighbours_skipped},
          {"points", tile.output.neighbour_points},
          {"points_left_to_neighbours", tile.output.points_left_to_neighbours},
          {"clusters_left_to_neighbours", tile.output.clusters_left_to_neighbours},
          {"clusters_split", tile.output.clusters_split_with_neighbours},
          {"footprints_left_to_neighbours", tile.footprints_left_to_neighbours},
          {"footprints_split", tile.footprints_split}};
}

namespace {

// Appends every point of `reader` (coordinates less `origin`, classes when `classes_wanted`,
// returns). Errors: the reader's.
Failure append_points(geo::PointReader& reader, const kernel::Vec3& origin, bool classes_wanted,
                      std::vector<kernel::Vec3>& raw, std::vector<std::uint8_t>& classes,
                      std::vector<std::uint8_t>& returns) {
  const bool has_classes = reader.info().fields.classification;
  geo::PointBatch batch;
  for (;;) {
    auto n = reader.read(batch, 1 << 16);
    if (!n.ok()) return failure_of(n.error());
    if (n.value() == 0) return {};
    for (const auto& p : batch.points) {
      raw.push_back(kernel::Vec3(p.x, p.y, p.z) - origin);
      if (classes_wanted) classes.push_back(has_classes ? p.classification : 0);
      returns.push_back(p.number_of_returns);
    }
  }
}

// The fit measures in metres (every fit option is a length in metres): the map from the
// tile's CRS units to metres, diag(h, h, v). Metres for a tile without a CRS. A geographic
// or geocentric CRS has no such map: an InputInvalid failure naming it.
Failure units_to_metres(const std::optional<geo::Crs>& crs, geo::UnitScale& out) {
  out = {};
  if (!crs) return {};
  if (!crs->is_projected()) {
    const bool geographic = crs->kind == geo::CrsKind::Geographic;
    return {ErrorCode::InputInvalid,
            "the tile's CRS (" + geo::describe_crs(*crs) + ") is " +
                (geographic ? "geographic: its x and y are angles"
                            : "geocentric: its z is not the height") +
                ", and the fit measures lengths and heights in a projected CRS; reproject the "
                "tile to one (e.g. its UTM zone) first"};
  }
  out = {crs->linear_unit.metres, crs->z_unit_metres()};
  return {};
}

// The fit's output, measured in metres, given back in the tile's units (`to_crs`): the
// primitives, the segments' surfaces and the structure points. A primitive with no exact
// form in those units (a sphere where heights count in another unit) is a rejection naming
// why.
void output_to_crs_units(fit::FitOutput& f, const geo::UnitScale& to_crs) {
  if (to_crs.identity()) return;
  std::vector<geo::ScenePrimitive> kept;
  kept.reserve(f.primitives.size());
  for (const geo::ScenePrimitive& p : f.primitives) {
    auto scaled = geo::scaled_primitive(p, to_crs);
    if (scaled.ok()) {
      kept.push_back(std::move(scaled).value());
      continue;
    }
    const long long points = p.quality ? p.quality->inliers : 0;
    f.rejected.push_back({p.id, scaled.error().message, points});
    --f.per_type[static_cast<std::size_t>(p.spec.type)];
    f.assigned_points -= points;
    f.unassigned_points += points;
  }
  f.primitives = std::move(kept);
  for (fit::Segment& s : f.segments) {
    s.surface.point = to_crs.apply(s.surface.point);
    s.surface.radius *= to_crs.horizontal;
    s.surface.radius2 *= to_crs.horizontal;
    s.rms *= to_crs.horizontal;
  }
  for (kernel::Vec3& p : f.structure_points) p = to_crs.apply(p);
}

}  // namespace

nlohmann::ordered_json footprints_record(const geo::FootprintSource& source,
                                         const FittedTile& tile) {
  return {{"source", source.source},
          {"read", tile.footprints_read},
          {"buildings", tile.output.footprint_regions},
          {"points", tile.output.footprint_points},
          {"skipped", tile.footprints_skipped},
          {"without_building", tile.output.footprints_without_building}};
}

Failure fit_tile(TileSource source, const std::string& name, const fit::FitPipelineOptions& options,
                 const std::string& crs_override, FittedTile& out,
                 const geo::FootprintSource& footprints, const TileNeighbours* around) {
  const auto start = std::chrono::steady_clock::now();
  out = FittedTile{};
  // Every point is read (the pipeline needs the whole tile), in the local frame. Only
  // coordinates, returns and classes are used: layered LAZ skips its other layers.
  geo::PointReadOptions read_options;
  read_options.all_attributes = false;
  read_options.region = source.region;
  kernel::Result<std::unique_ptr<geo::PointReader>> opened =
      kernel::Error{kernel::ErrorCode::InvalidArgument, "unopened"};
  if (source.remote) {
    auto las = geo::LasReader::open_source(std::move(source.remote), read_options);
    if (las.ok()) {
      opened = std::unique_ptr<geo::PointReader>(std::move(las).value());
    } else {
      opened = las.error();
    }
  } else {
    opened = geo::open_point_file(source.path, read_options);
  }
  if (!opened.ok()) return failure_of(opened.error());
  geo::PointReader& reader = *opened.value();
  std::array<double, 3> origin{0.0, 0.0, 0.0};
  std::string crs_text;
  const auto* las = dynamic_cast<const geo::LasReader*>(&reader);
  // The CRS as the run records it: "EPSG:h[+v]" for EPSG codes, else WKT 1.
  auto crs_label = [](const geo::Crs& v) {
    if (v.epsg == 0) return geo::crs_to_wkt1(v);
    std::string text = "EPSG:" + std::to_string(v.epsg);
    if (v.vertical && v.vertical->epsg != 0) text += "+" + std::to_string(v.vertical->epsg);
    return text;
  };
  std::optional<geo::Crs> given;
  if (!crs_override.empty()) {
    auto parsed = geo::crs_from_config(crs_override);
    if (!parsed.ok()) {
      return {ErrorCode::ConfigInvalid, "CRS " + crs_override + ": " + parsed.error().message};
    }
    given = std::move(parsed).value();
    crs_text = crs_label(*given);
  }
  std::optional<geo::Crs> used = given;
  if (las != nullptr) {
    origin = las->header().offset;
    auto own = geo::las_file_crs(las->crs(), "");
    if (!given && own.ok()) used = own.value();
    if (given && own.ok()) {
      // The run's CRS is for tiles without one; a tile that says otherwise is an error.
      if (auto diff = geo::crs_difference(own.value(), *given)) {
        return {ErrorCode::InputInvalid, "the tile's CRS (" + geo::describe_crs(own.value()) +
                                             ") differs from run.crs (" + crs_override + ": " +
                                             geo::describe_crs(*given) + "): " + *diff};
      }
    } else if (!given && own.ok()) {
      crs_text = crs_label(own.value());
    }
  }
  geo::UnitScale to_metres;
  if (Failure f = units_to_metres(used, to_metres); !f.ok()) return f;
  std::vector<kernel::Vec3> raw;
  std::vector<std::uint8_t> classes, returns;
  const bool has_classes = reader.info().fields.classification;
  // The tile's records in one allocation when its header says how many: growing by doubling
  // holds up to twice the points at the peak. Not for a region (fewer are read), and never
  // more than one point per byte of the file (a header is not trusted further).
  if (!read_options.region && !source.remote && reader.info().point_count) {
    std::error_code ec;
    const std::uintmax_t bytes = std::filesystem::file_size(source.path, ec);
    const std::uint64_t n = ec ? 0 : std::min<std::uint64_t>(*reader.info().point_count, bytes);
    raw.reserve(n);
    returns.reserve(n);
    if (has_classes) classes.reserve(n);
  }
  if (Failure f = append_points(reader, kernel::Vec3::Zero(), has_classes, raw, classes, returns);
      !f.ok()) {
    return f;
  }
  // The tile-local frame: the LAS offset when the points lie within 10 km of it, else (other
  // formats, or an offset of 0 under national coordinates of 1e5 m, as AHN3's) the floor of
  // the smallest x and y: the fit computes in coordinates of the tile's size, not the CRS's.
  if (!raw.empty()) {
    double x0 = INFINITY, y0 = INFINITY, far = 0.0;
    for (const auto& p : raw) {
      if (!p.allFinite()) continue;
      x0 = std::min(x0, p.x());
      y0 = std::min(y0, p.y());
      far = std::max({far, std::abs(p.x() - origin[0]), std::abs(p.y() - origin[1])});
    }
    if (std::isfinite(x0) && (las == nullptr || far > 1e4)) {
      origin = {std::floor(x0), std::floor(y0), las == nullptr ? 0.0 : origin[2]};
    }
  }
  // A read that holds the neighbours' points too: each point is its owner's (decided in CRS
  // coordinates, as every tile decides it).
  std::vector<std::uint8_t> foreign;
  if (around != nullptr) {
    foreign.reserve(raw.size());
    for (const auto& p : raw) {
      const bool own = !around->own_read_is_shared || owns_point(around->where, {p.x(), p.y()});
      foreign.push_back(own ? 0 : 1);
    }
  }
  const kernel::Vec3 o(origin[0], origin[1], origin[2]);
  for (auto& p : raw) p -= o;

  // The neighbours' points in the read region (those of a tile in another CRS are not read).
  const std::size_t own_points = raw.size();
  if (around != nullptr) {
    out.neighbours_skipped = around->skipped;
    const Extent r = around->where.read_region();
    geo::PointReadOptions near_options = read_options;
    near_options.region = geo::Bounds3{{r[0], r[1], -INFINITY}, {r[2], r[3], INFINITY}};
    for (std::size_t k = 0; k < around->paths.size(); ++k) {
      if (around->paths[k].empty()) continue;  // not near enough
      const std::string& input = around->where.neighbours[k].input;
      // A neighbour that cannot be read is its own job's failure; here it is named.
      auto near = geo::open_point_file(around->paths[k], near_options);
      if (!near.ok()) {
        out.neighbours_skipped.push_back(input + ": " + near.error().message);
        continue;
      }
      const auto* near_las = dynamic_cast<const geo::LasReader*>(near.value().get());
      if (las != nullptr && near_las != nullptr) {
        auto own = geo::las_file_crs(las->crs(), "");
        auto theirs = geo::las_file_crs(near_las->crs(), "");
        if (own.ok() != theirs.ok() ||
            (own.ok() && geo::crs_difference(own.value(), theirs.value()))) {
          out.neighbours_skipped.push_back(input + ": its CRS differs from this tile's");
          continue;
        }
      }
      const std::size_t before = raw.size();
      if (Failure f = append_points(*near.value(), o, has_classes, raw, classes, returns);
          !f.ok()) {
        raw.resize(before), returns.resize(before);
        if (has_classes) classes.resize(before);
        out.neighbours_skipped.push_back(input + ": " + f.message);
        continue;
      }
      ++out.neighbours_read;
    }
    foreign.resize(raw.size(), 1);
  }
  out.read_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  // Footprints meeting the points' extent, cut to it, in the tile's frame; among neighbours,
  // those meeting the read region, each also cut to the tile's extent.
  std::vector<geo::Footprint> buildings;
  // How far a footprint's points reach past it (kFootprintBuffer, metres), in the tile's units.
  const double buffer = fit::kFootprintBuffer / to_metres.horizontal;
  if (!footprints.source.empty()) {
    double x0 = INFINITY, y0 = INFINITY, x1 = -INFINITY, y1 = -INFINITY;
    for (const auto& p : std::span(raw).first(own_points)) {
      if (!p.allFinite()) continue;
      x0 = std::min(x0, p.x()), y0 = std::min(y0, p.y());
      x1 = std::max(x1, p.x()), y1 = std::max(y1, p.y());
    }
    if (x0 <= x1) {
      // Cut to the points' extent: a building ends where the tile's data ends.
      geo::FootprintQuery query;
      query.target_crs = crs_text;
      query.bbox = std::array<double, 4>{x0 + o.x(), y0 + o.y(), x1 + o.x(), y1 + o.y()};
      query.clip = {*query.bbox};
      if (around != nullptr) {
        // Among neighbours: over the read region, cut to where the tiles' data is (their
        // extents grown by the footprint buffer: no slit along the seams between them), and
        // each also cut to this tile's extent (for a building fitted in parts).
        // Footprints whose buffer (eaves) reaches into the read region hold some of its points.
        query.bbox = grown(around->where.read_region(), buffer);
        query.clip = {grown(around->where.self.extent, buffer)};
        for (const TileExtent& t : around->where.neighbours) {
          query.clip.push_back(grown(t.extent, buffer));
        }
        query.cut = around->where.self.extent;
      }
      auto read = geo::read_footprints(footprints, query);
      if (!read.ok()) {
        return {read.error().code == kernel::ErrorCode::IoError ? ErrorCode::Io
                                                                : ErrorCode::InputInvalid,
                read.error().message};
      }
      buildings = std::move(read.value().footprints);
      out.footprints_skipped = std::move(read.value().skipped);
      for (auto& b : buildings) {
        for (auto* polygons : {&b.polygons, &b.cut}) {
          for (auto& polygon : *polygons) {
            for (auto& q : polygon.outer) q -= kernel::Vec2(o.x(), o.y());
            for (auto& h : polygon.holes) {
              for (auto& q : h) q -= kernel::Vec2(o.x(), o.y());
            }
          }
        }
      }
    }
    out.footprints_read = static_cast<long long>(buildings.size());
  }

  // Among neighbours: which buildings are this tile's (tile_share.h), in CRS coordinates.
  std::vector<fit::ShareKind> kinds;
  fit::TileShare share;
  if (around != nullptr) {
    const kernel::Vec2 o2(o.x(), o.y());
    for (geo::Footprint& b : buildings) {
      // From the footprint as every tile reads it (its envelope before any cut).
      const kernel::Vec2 reach(buffer, buffer);
      const kernel::Vec2 lo(b.envelope[0], b.envelope[1]), hi(b.envelope[2], b.envelope[3]);
      fit::ShareKind kind = footprint_share(around->where, lo - reach, hi + reach);
      if (kind == fit::ShareKind::own_points && b.cut.empty()) kind = fit::ShareKind::none;
      if (kind == fit::ShareKind::own_points) {
        b.polygons = b.cut;  // this tile's part
        out.footprints_split.push_back(b.id);
      }
      if (kind == fit::ShareKind::none) ++out.footprints_left_to_neighbours;
      kinds.push_back(kind);
    }
    share.foreign = foreign;
    share.footprints = kinds;
    // The fit measures in metres: back to the tile's units.
    const double h = to_metres.horizontal;
    share.clusters = [around, o2, h](const kernel::Vec2& lo, const kernel::Vec2& hi, double tol) {
      return cluster_share(around->where, lo / h + o2, hi / h + o2, tol / h);
    };
  }

  // The points and footprints in metres (tile-local): the fit's lengths are metres.
  if (!to_metres.identity()) {
    for (auto& p : raw) p = to_metres.apply(p);
    for (auto& b : buildings) {
      for (auto* polygons : {&b.polygons, &b.cut}) {
        for (auto& polygon : *polygons) {
          for (auto& q : polygon.outer) q *= to_metres.horizontal;
          for (auto& ring : polygon.holes) {
            for (auto& q : ring) q *= to_metres.horizontal;
          }
        }
      }
    }
  }

  // Returns per pulse: only formats that record them (every LAS and LAZ).
  if (las == nullptr) returns.clear();
  auto fitted = fit::fit_point_cloud(raw, classes, options, buildings, returns,
                                     around != nullptr ? &share : nullptr);
  if (!fitted.ok()) return {ErrorCode::ConfigInvalid, fitted.error().message};
  out.output = std::move(fitted).value();
  output_to_crs_units(out.output, to_metres.inverse());
  out.origin = origin;
  out.scene.name = name;
  out.scene.seed = options.ransac.seed;
  if (!crs_text.empty() || las != nullptr) out.scene.frame = geo::SceneFrame{crs_text, origin};
  out.scene.primitives = out.output.primitives;
  return {};
}

}  // namespace csgtile::worker::city
