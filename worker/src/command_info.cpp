// `csgtile info FILE|URL [--json] [--scan]`: what a point-cloud file says about itself —
// version, point format, counts, bounds, scale/offset, CRS (interpreted, with its records),
// VLRs/EVLRs, extra bytes, a COPC file's octree — and the problems the reader found. A URL
// (http, https, s3) is read by range requests: only the header, records and pages shown. LAS
// headers are reported without reading the points unless
// --scan is given; PLY/PCD/XYZ have no header bounds, so their points are always scanned.

#include <algorithm>
#include <cinttypes>
#include <cstdio>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>

#include "commands.h"
#include "csgtile/geo/las.h"
#include "csgtile/geo/point_reader.h"
#include "csgtile/worker/errors.h"
#include "fetch/fetch.h"

namespace csgtile::worker::detail {

namespace {

using Json = nlohmann::ordered_json;

struct InfoOptions {
  std::string file;
  bool json = false;
  bool scan = false;
  std::string crs;  ///< the CRS to assume when the file has none (config syntax)
};

Json optional_code(const std::optional<std::uint16_t>& code) {
  return code ? Json(*code) : Json(nullptr);
}

Json bounds_json(const geo::Bounds3& b) {
  if (b.empty()) return nullptr;
  return Json{{"min", {b.min[0], b.min[1], b.min[2]}}, {"max", {b.max[0], b.max[1], b.max[2]}}};
}

Json record_json(const geo::LasRecord& r) {
  return Json{{"user_id", r.user_id},
              {"record_id", r.record_id},
              {"length", r.length},
              {"description", r.description}};
}

Json extra_json(const geo::ExtraLayout& layout) {
  Json dims = Json::array();
  for (const auto& d : layout.dimensions) {
    Json j{{"name", d.name},
           {"type", geo::extra_type_name(d.type)},
           {"elements", d.elements},
           {"byte_offset", d.byte_offset},
           {"description", d.description}};
    if (d.scale) j["scale"] = *d.scale;
    if (d.offset) j["offset"] = *d.offset;
    if (d.no_data) j["no_data"] = *d.no_data;
    if (d.minimum) j["min"] = *d.minimum;
    if (d.maximum) j["max"] = *d.maximum;
    dims.push_back(std::move(j));
  }
  return Json{{"bytes_per_point", layout.record_size},
              {"undescribed_bytes", layout.undescribed_bytes()},
              {"dimensions", std::move(dims)}};
}

Json crs_json(const geo::LasCrsRecords& crs) {
  Json keys = Json::array();
  for (const auto& k : crs.keys) {
    Json j{{"id", k.id}, {"location", k.location}, {"count", k.count}};
    if (k.location == 0)
      j["value"] = k.value_offset;
    else if (k.location == 34736)
      j["value"] = k.doubles;
    else if (k.location == 34737)
      j["value"] = k.ascii;
    keys.push_back(std::move(j));
  }
  return Json{{"projected_cs", optional_code(crs.projected_cs)},
              {"geographic_cs", optional_code(crs.geographic_cs)},
              {"vertical_cs", optional_code(crs.vertical_cs)},
              {"projected_linear_units", optional_code(crs.projected_linear_units)},
              {"vertical_units", optional_code(crs.vertical_units)},
              {"model_type", optional_code(crs.model_type)},
              {"wkt", crs.wkt ? Json(*crs.wkt) : Json(nullptr)},
              {"wkt_from_evlr", crs.wkt_from_evlr},
              {"wkt_flag", crs.wkt_flag},
              {"liblas_wkt", crs.liblas_wkt ? Json(*crs.liblas_wkt) : Json(nullptr)},
              {"geotiff_keys", std::move(keys)}};
}

/// The CRS the file's records (or --crs) resolve to, interpreted.
Json resolved_crs_json(const kernel::Result<geo::Crs>& crs) {
  if (!crs.ok()) return Json{{"error", crs.error().message}};
  const geo::Crs& c = crs.value();
  return Json{{"epsg", c.epsg == 0 ? Json(nullptr) : Json(c.epsg)},
              {"name", c.name},
              {"kind", c.is_projected() ? "projected" : "geographic"},
              {"description", geo::describe_crs(c)},
              {"vertical_epsg",
               c.vertical && c.vertical->epsg != 0 ? Json(c.vertical->epsg) : Json(nullptr)},
              {"source", c.source},
              {"to_wgs84", c.datum.to_wgs84_source},
              {"heights", c.vertical ? Json(c.vertical->to_ellipsoidal_source) : Json(nullptr)},
              {"warnings", c.warnings},
              {"error", nullptr}};
}

std::string code_text(const std::optional<std::uint16_t>& code) {
  if (!code) return "";
  if (*code == geo::kGeoKeyUserDefined) return "user-defined";
  return "EPSG:" + std::to_string(*code);
}

std::string shorten(const std::string& text, std::size_t size) {
  std::string one_line;
  for (char c : text) one_line += (c == '\n' || c == '\r') ? ' ' : c;
  return one_line.size() <= size ? one_line : one_line.substr(0, size) + "…";
}

void print_bounds(const char* label, const geo::Bounds3& b) {
  if (b.empty()) {
    std::printf("%-13s(none)\n", label);
    return;
  }
  std::printf("%-13sx [%.10g, %.10g]  y [%.10g, %.10g]  z [%.10g, %.10g]\n", label, b.min[0],
              b.max[0], b.min[1], b.max[1], b.min[2], b.max[2]);
}

int run_info(const InfoOptions& o) {
  Json out;
  out["file"] = o.file;
  auto fail = [&](const Failure& f) { return detail::report_failure("info", f, o.json, out); };

  std::unique_ptr<geo::PointReader> reader;
  geo::LasReader* las = nullptr;
  std::shared_ptr<fetch::RangeStats> fetched;
  const bool remote = fetch::is_remote_url(o.file);
  auto format = remote ? kernel::Result<geo::PointFileFormat>(geo::PointFileFormat::Las)
                       : geo::detect_point_format(o.file);
  if (!format.ok()) return fail(failure_of(format.error()));
  if (remote) {
    // A URL (http, https, s3): LAS, LAZ or COPC read by range requests, only what is shown.
    fetched = std::make_shared<fetch::RangeStats>();
    std::unique_ptr<geo::LasReader> opened;
    if (Failure f = fetch::open_las(o.file, fetch::Policy{}, opened, fetched); !f.ok()) {
      return fail(f);
    }
    las = opened.get();
    reader = std::move(opened);
  } else if (format.value() == geo::PointFileFormat::Las) {
    auto opened = geo::LasReader::open(o.file);
    if (!opened.ok()) return fail(failure_of(opened.error()));
    las = opened.value().get();
    reader = std::move(opened).value();
  } else {
    auto opened = geo::open_point_file(o.file);
    if (!opened.ok()) return fail(failure_of(opened.error()));
    reader = std::move(opened).value();
  }

  // Scan the points when asked, and always for formats without header bounds.
  const bool scan = o.scan || las == nullptr;
  std::optional<kernel::Error> scan_error;
  if (scan) {
    geo::PointBatch batch;
    for (;;) {
      auto n = reader->read(batch, 1 << 16);
      if (!n.ok()) {
        scan_error = n.error();
        break;
      }
      if (n.value() == 0) break;
    }
  }

  const geo::PointCloudInfo& info = reader->info();
  out["format"] = geo::point_file_format_name(info.format);
  out["description"] = info.description;
  if (las != nullptr) {
    const geo::LasHeader& h = las->header();
    out["version"] = std::to_string(h.version_major) + "." + std::to_string(h.version_minor);
    out["point_format"] = h.point_format;
    out["record_length"] = h.record_length;
    out["system_identifier"] = h.system_identifier;
    out["generating_software"] = h.generating_software;
    out["creation"] = {{"day", h.creation_day}, {"year", h.creation_year}};
    out["global_encoding"] = h.global_encoding;
  }
  out["point_count"] = info.point_count ? Json(*info.point_count) : Json(nullptr);
  if (las != nullptr) {
    const geo::LasHeader& h = las->header();
    out["points_by_return"] = h.points_by_return;
    out["scale"] = h.scale;
    out["offset"] = h.offset;
  }
  out["bounds"] = info.bounds ? bounds_json(*info.bounds) : Json(nullptr);
  if (scan) {
    out["points_read"] = reader->points_read();
    out["scanned_bounds"] = bounds_json(reader->bounds_read());
  }
  if (las != nullptr) {
    out["crs"] = crs_json(las->crs());
    out["crs"]["resolved"] = resolved_crs_json(geo::las_file_crs(las->crs(), o.crs));
    Json vlrs = Json::array();
    for (const auto& r : las->vlrs()) vlrs.push_back(record_json(r));
    Json evlrs = Json::array();
    for (const auto& r : las->evlrs()) evlrs.push_back(record_json(r));
    out["vlrs"] = std::move(vlrs);
    out["evlrs"] = std::move(evlrs);
  }
  out["extra_bytes"] = info.extra ? extra_json(*info.extra) : Json(nullptr);
  // COPC: the octree as its hierarchy says (the pages are read; no point chunk is).
  std::optional<std::vector<geo::CopcNode>> copc_nodes;
  if (las != nullptr && las->copc()) {
    auto nodes = las->copc_hierarchy();
    if (!nodes.ok()) return fail(failure_of(nodes.error()));
    copc_nodes = std::move(nodes).value();
    const geo::CopcInfo& c = *las->copc();
    int depth = 0;
    std::uint64_t points = 0;
    for (const auto& n : *copc_nodes) {
      depth = std::max(depth, n.depth);
      points += n.points;
    }
    out["copc"] = {{"center", c.center},
                   {"halfsize", c.halfsize},
                   {"spacing", c.spacing},
                   {"nodes", copc_nodes->size()},
                   {"max_depth", depth},
                   {"points", points},
                   {"gpstime", {c.gpstime_minimum, c.gpstime_maximum}}};
  }
  if (fetched) out["fetched"] = {{"requests", fetched->requests}, {"bytes", fetched->bytes}};
  out["warnings"] = reader->warnings();

  if (scan_error) {
    return fail(failure_of(*scan_error));
  }
  if (o.json) {
    out["error"] = nullptr;
    std::cout << out.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace) << "\n";
    return 0;
  }

  std::printf("%-13s%s\n", "file", o.file.c_str());
  std::printf("%-13s%s", "format", info.description.c_str());
  if (las != nullptr) {
    const geo::LasHeader& h = las->header();
    std::printf(" (record %u bytes, %u extra)", unsigned{h.record_length},
                unsigned{h.extra_bytes_per_point()});
    std::printf("\n%-13s%s / %s, created day %u of %u", "software", h.system_identifier.c_str(),
                h.generating_software.c_str(), unsigned{h.creation_day}, unsigned{h.creation_year});
  }
  std::printf("\n");
  if (info.point_count) std::printf("%-13s%" PRIu64 "\n", "points", *info.point_count);
  if (las != nullptr) {
    const geo::LasHeader& h = las->header();
    std::printf("%-13s%.17g %.17g %.17g\n", "scale", h.scale[0], h.scale[1], h.scale[2]);
    // + 0.0 prints a stored -0 as 0.
    std::printf("%-13s%.17g %.17g %.17g\n", "offset", h.offset[0] + 0.0, h.offset[1] + 0.0,
                h.offset[2] + 0.0);
  }
  if (info.bounds) print_bounds("bounds", *info.bounds);
  if (scan) {
    std::printf("%-13s%" PRIu64 "\n", "points read", reader->points_read());
    print_bounds("scanned", reader->bounds_read());
  }
  if (las != nullptr) {
    const geo::LasCrsRecords& crs = las->crs();
    std::string text;
    auto add = [&](const char* what, const std::string& value) {
      if (value.empty()) return;
      if (!text.empty()) text += ", ";
      text += std::string(what) + " " + value;
    };
    add("projected", code_text(crs.projected_cs));
    add("geographic", code_text(crs.geographic_cs));
    add("vertical", code_text(crs.vertical_cs));
    add("linear units", code_text(crs.projected_linear_units));
    add("vertical units", code_text(crs.vertical_units));
    if (crs.has_geotiff && text.empty()) text = "GeoTIFF keys without EPSG codes";
    if (crs.empty()) text = "none in the file";
    const auto resolved = geo::las_file_crs(crs, o.crs);
    if (resolved.ok()) {
      std::printf("%-13s%s%s\n", "crs", geo::describe_crs(resolved.value()).c_str(),
                  crs.empty() ? " (from --crs)" : "");
      for (const auto& w : resolved.value().warnings) std::printf("  %s\n", w.c_str());
    } else {
      std::printf("%-13s%s\n", "crs", resolved.error().message.c_str());
    }
    std::printf("%-13s%s\n", "crs records", text.c_str());
    if (crs.wkt) {
      std::printf("%-13s%s%s\n", "wkt", crs.wkt_from_evlr ? "(EVLR) " : "",
                  shorten(*crs.wkt, 100).c_str());
    } else if (crs.liblas_wkt) {
      std::printf("%-13s(libLAS VLR) %s\n", "wkt", shorten(*crs.liblas_wkt, 100).c_str());
    }
    auto list = [](const char* label, const std::vector<geo::LasRecord>& records) {
      std::printf("%-13s%zu\n", label, records.size());
      for (const auto& r : records) {
        std::printf("  %-16s %6u %10" PRIu64 " bytes  %s\n", r.user_id.c_str(),
                    unsigned{r.record_id}, r.length, r.description.c_str());
      }
    };
    list("vlrs", las->vlrs());
    if (las->header().version_minor >= 4) list("evlrs", las->evlrs());
  }
  if (info.extra) {
    std::printf("%-13s%zu bytes per point", "extra bytes", info.extra->record_size);
    if (info.extra->undescribed_bytes() > 0) {
      std::printf(" (%zu undescribed)", info.extra->undescribed_bytes());
    }
    std::printf("\n");
    for (const auto& d : info.extra->dimensions) {
      std::printf("  %-24s %-8s x%d at +%zu", d.name.c_str(), geo::extra_type_name(d.type),
                  d.elements, d.byte_offset);
      if (d.scale) std::printf("  scale %.10g", *d.scale);
      if (d.offset) std::printf("  offset %.10g", *d.offset);
      std::printf("\n");
    }
  }
  if (out.contains("copc")) {
    const Json& c = out["copc"];
    std::printf(
        "%-13s%s nodes, depth 0-%s, %s points in the hierarchy, root half size %.10g, "
        "spacing %.10g\n",
        "copc", c["nodes"].dump().c_str(), c["max_depth"].dump().c_str(),
        c["points"].dump().c_str(), c["halfsize"].get<double>(), c["spacing"].get<double>());
  }
  if (fetched) {
    std::printf("%-13s%" PRIu64 " bytes in %" PRIu64 " range requests\n", "fetched", fetched->bytes,
                fetched->requests);
  }
  std::printf("%-13s%zu\n", "warnings", reader->warnings().size());
  for (const auto& w : reader->warnings()) std::printf("  %s\n", w.c_str());
  return 0;
}

}  // namespace

void register_info(CLI::App& app, Action& action) {
  auto* cmd = app.add_subcommand(
      "info",
      "Describe a point-cloud file (LAS, PLY, PCD, XYZ): version, format, counts, "
      "bounds, scale/offset, CRS records, VLRs/EVLRs, extra bytes and warnings");
  auto options = std::make_shared<InfoOptions>();
  cmd->add_option("FILE", options->file, "Point-cloud file")->required();
  cmd->add_flag("--json", options->json, "Print one JSON object");
  cmd->add_flag("--scan", options->scan,
                "Read every point: recomputed bounds and count, and the warnings only the "
                "points reveal (always on for PLY/PCD/XYZ)");
  cmd->add_option("--crs", options->crs,
                  "CRS to assume when the file has none, e.g. EPSG:28992 or EPSG:28992+5709");
  cmd->callback([&action, options] { action = [options] { return run_info(*options); }; });
}

}  // namespace csgtile::worker::detail
