#include "export/report.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstddef>
#include <limits>
#include <set>
#include <string_view>
#include <system_error>

#include <nlohmann/json.hpp>

#include "csgtile/worker/files.h"
#include "csgtile/worker/publish.h"
#include "export/report_assets.h"

#ifndef CSGTILE_VERSION
#define CSGTILE_VERSION "unknown"
#endif

namespace csgtile::worker {
namespace {

constexpr double kMapSize = 720.0;   // the top view's longer side, px
constexpr double kMapMargin = 12.0;  // px around the top view
constexpr int kLabelWidth = 200;     // bar charts: label column, px
constexpr int kBarWidth = 500;       // bar charts: longest bar, px
constexpr int kRowHeight = 22;       // bar charts: one row, px

Failure input_invalid(std::string message) {
  return {ErrorCode::InputInvalid, "run report: " + std::move(message)};
}

std::string escape_html(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&#39;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

// "1 object", "2 objects".
std::string count_of(std::size_t count, const std::string& noun) {
  return std::to_string(count) + " " + noun + (count == 1 ? "" : "s");
}

// A JavaScript string literal (JSON, ASCII only).
std::string js_string(std::string_view text) {
  return nlohmann::json(std::string(text)).dump(-1, ' ', true);
}

// Fixed-point text, the same on every locale and platform; "n/a" when not finite.
std::string fixed(double value, int decimals) {
  if (!std::isfinite(value)) return "n/a";
  if (value == 0.0) value = 0.0;  // no "-0.00"
  char buffer[64];
  auto [end, error] =
      std::to_chars(buffer, buffer + sizeof buffer, value, std::chars_format::fixed, decimals);
  if (error != std::errc()) return "n/a";
  std::string text(buffer, end);
  if (text.find_first_not_of("-0.") == std::string::npos) text = text.substr(text[0] == '-');
  return text;
}

std::string base64(std::string_view bytes) {
  static constexpr char kAlphabet[] =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  std::size_t i = 0;
  for (; i + 3 <= bytes.size(); i += 3) {
    const unsigned v = (static_cast<unsigned char>(bytes[i]) << 16) |
                       (static_cast<unsigned char>(bytes[i + 1]) << 8) |
                       static_cast<unsigned char>(bytes[i + 2]);
    out += kAlphabet[(v >> 18) & 63];
    out += kAlphabet[(v >> 12) & 63];
    out += kAlphabet[(v >> 6) & 63];
    out += kAlphabet[v & 63];
  }
  if (const std::size_t rest = bytes.size() - i; rest > 0) {
    unsigned v = static_cast<unsigned char>(bytes[i]) << 16;
    if (rest == 2) v |= static_cast<unsigned char>(bytes[i + 1]) << 8;
    out += kAlphabet[(v >> 18) & 63];
    out += kAlphabet[(v >> 12) & 63];
    out += rest == 2 ? kAlphabet[(v >> 6) & 63] : '=';
    out += '=';
  }
  return out;
}

// The path as the page shows it: relative to the run directory when inside it (so that the
// page does not depend on where the run directory is; `inside` set), else as given.
std::string shown_path(const std::filesystem::path& file, const std::filesystem::path& run_dir,
                       bool& inside) {
  std::error_code error;
  const auto absolute_file = std::filesystem::absolute(file, error).lexically_normal();
  const auto absolute_run = std::filesystem::absolute(run_dir, error).lexically_normal();
  const auto relative = absolute_file.lexically_relative(absolute_run);
  inside = !error && !relative.empty() && *relative.begin() != "..";
  return inside ? relative.generic_string() : file.generic_string();
}

struct CellGlb {
  std::string bytes;   // the GLB, when usable
  std::string reason;  // why not, otherwise (empty when the cell has no glb_path)
  std::string link;    // relative to report/, when the GLB is inside the run directory
};

CellGlb read_glb(const ReportCell& cell, const std::filesystem::path& run_dir) {
  CellGlb glb;
  if (cell.glb_path.empty()) return glb;
  bool inside = false;
  const std::string shown = shown_path(cell.glb_path, run_dir, inside);
  if (!std::filesystem::exists(cell.glb_path)) {
    glb.reason = "glTF missing: " + shown;
    return glb;
  }
  std::string bytes;
  if (!read_file_bytes(cell.glb_path, bytes).ok()) {
    glb.reason = "glTF unreadable: " + shown;
  } else if (bytes.size() < 12 || bytes.compare(0, 4, "glTF") != 0) {
    glb.reason = "not a GLB file: " + shown;
  } else {
    glb.bytes = std::move(bytes);
    if (inside) glb.link = "../" + shown;
  }
  return glb;
}

Failure check_input(const ReportInput& in) {
  std::set<std::string> ids;
  for (const ReportCell& cell : in.cells) {
    if (cell.id.empty() || !is_safe_key(cell.id) || cell.id.find('/') != std::string::npos) {
      return input_invalid("cell id \"" + cell.id + "\" is not one of [A-Za-z0-9._-]+");
    }
    if (!ids.insert(cell.id).second) return input_invalid("cell id \"" + cell.id + "\" repeated");
    const auto& b = cell.bounds;
    if (!std::all_of(b.begin(), b.end(), [](double v) { return std::isfinite(v); }) ||
        b[0] > b[2] || b[1] > b[3]) {
      return input_invalid("cell " + cell.id + ": bounds not finite or inverted");
    }
    for (const ReportObject& object : cell.objects) {
      for (const auto& ring : object.footprint) {
        for (const auto& point : ring) {
          if (!std::isfinite(point[0]) || !std::isfinite(point[1])) {
            return input_invalid("cell " + cell.id + ", object " + object.id +
                                 ": footprint point not finite");
          }
        }
      }
    }
  }
  return {};
}

// Horizontal bars, one row per entry, the value written after each bar.
std::string bar_chart(const std::vector<std::pair<std::string, double>>& rows,
                      std::string_view label, int decimals) {
  double longest = 0.0;
  for (const auto& row : rows) longest = std::max(longest, row.second);
  if (longest <= 0.0) longest = 1.0;
  const int height = static_cast<int>(rows.size()) * kRowHeight + 8;
  std::string svg = "<svg width=\"" + std::to_string(kLabelWidth + kBarWidth + 90) +
                    "\" height=\"" + std::to_string(height) + "\" role=\"img\" aria-label=\"" +
                    escape_html(label) + "\">\n";
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const int y = static_cast<int>(i) * kRowHeight + 4;
    const double width = std::max(0.0, rows[i].second) / longest * kBarWidth;
    svg += "<text x=\"" + std::to_string(kLabelWidth - 8) + "\" y=\"" + std::to_string(y + 14) +
           "\" text-anchor=\"end\">" + escape_html(rows[i].first) + "</text>";
    svg += "<rect class=\"bar\" x=\"" + std::to_string(kLabelWidth) + "\" y=\"" +
           std::to_string(y + 2) + "\" width=\"" + fixed(std::max(width, 1.0), 1) + "\" height=\"" +
           std::to_string(kRowHeight - 6) + "\"/>";
    svg += "<text x=\"" + fixed(kLabelWidth + width + 6, 1) + "\" y=\"" + std::to_string(y + 14) +
           "\">" + fixed(rows[i].second, decimals) + "</text>\n";
  }
  svg += "</svg>\n";
  return svg;
}

// 1, 2 or 5 times a power of ten, at least `value`.
double nice_step(double value) {
  const double power = std::pow(10.0, std::floor(std::log10(value)));
  for (double factor : {1.0, 2.0, 5.0, 10.0}) {
    if (factor * power >= value) return factor * power;
  }
  return 10.0 * power;
}

std::string rms_histogram(const std::vector<double>& all) {
  std::vector<double> values;
  for (double v : all) {
    if (std::isfinite(v) && v >= 0.0) values.push_back(v);
  }
  const std::size_t left_out = all.size() - values.size();
  std::string html;
  if (values.empty()) {
    html += "<p class=\"note\">No fitted primitives.</p>\n";
  } else {
    std::sort(values.begin(), values.end());
    const auto quantile = [&](double q) {
      return values[static_cast<std::size_t>(
          std::llround(q * static_cast<double>(values.size() - 1)))];
    };
    const std::size_t wanted = std::clamp<std::size_t>(
        static_cast<std::size_t>(std::ceil(std::sqrt(values.size()))), 5, 30);
    const double largest = values.back();
    const double step = largest > 0.0 ? nice_step(largest / static_cast<double>(wanted)) : 0.001;
    const std::size_t bins =
        std::max<std::size_t>(1, static_cast<std::size_t>(std::ceil(largest / step)));
    std::vector<std::size_t> counts(bins, 0);
    for (double v : values) {
      counts[std::min(bins - 1, static_cast<std::size_t>(v / step))] += 1;
    }
    const std::size_t most = *std::max_element(counts.begin(), counts.end());
    const double plot_width = 600.0, plot_height = 180.0, left = 50.0, top = 10.0;
    const double bar = plot_width / static_cast<double>(bins);
    html += "<p>" + std::to_string(values.size()) + " fitted primitives; RMS median " +
            fixed(quantile(0.5) * 1000.0, 2) + " mm, 95th percentile " +
            fixed(quantile(0.95) * 1000.0, 2) + " mm, largest " + fixed(largest * 1000.0, 2) +
            " mm.</p>\n";
    html += "<svg width=\"" + fixed(left + plot_width + 20, 0) + "\" height=\"" +
            fixed(top + plot_height + 44, 0) +
            "\" role=\"img\" aria-label=\"fit residual histogram\">\n";
    for (std::size_t i = 0; i < bins; ++i) {
      const double h = static_cast<double>(counts[i]) / static_cast<double>(most) * plot_height;
      const double x = left + static_cast<double>(i) * bar;
      html += "<rect class=\"bar\" x=\"" + fixed(x + 1, 1) + "\" y=\"" +
              fixed(top + plot_height - h, 1) + "\" width=\"" + fixed(std::max(bar - 2, 1.0), 1) +
              "\" height=\"" + fixed(h, 1) + "\"><title>" +
              fixed(static_cast<double>(i) * step * 1000.0, 2) + "–" +
              fixed(static_cast<double>(i + 1) * step * 1000.0, 2) +
              " mm: " + std::to_string(counts[i]) + "</title></rect>\n";
    }
    html += "<line class=\"axis\" x1=\"" + fixed(left, 0) + "\" y1=\"" +
            fixed(top + plot_height, 0) + "\" x2=\"" + fixed(left + plot_width, 0) + "\" y2=\"" +
            fixed(top + plot_height, 0) + "\"/>\n";
    const std::size_t label_every = std::max<std::size_t>(1, bins / 6);
    const int label_decimals = step >= 0.001 ? 0 : step >= 0.0001 ? 1 : 2;
    for (std::size_t i = 0; i <= bins; i += label_every) {
      html += "<text x=\"" + fixed(left + static_cast<double>(i) * bar, 1) + "\" y=\"" +
              fixed(top + plot_height + 16, 0) + "\" text-anchor=\"middle\">" +
              fixed(static_cast<double>(i) * step * 1000.0, label_decimals) + "</text>";
    }
    html += "<text x=\"" + fixed(left + plot_width / 2, 0) + "\" y=\"" +
            fixed(top + plot_height + 36, 0) + "\" text-anchor=\"middle\">RMS residual (mm)</text>";
    html += "<text x=\"" + fixed(left - 6, 0) + "\" y=\"" + fixed(top + 10, 0) +
            "\" text-anchor=\"end\">" + std::to_string(most) + "</text>";
    html += "<text x=\"" + fixed(left - 6, 0) + "\" y=\"" + fixed(top + plot_height, 0) +
            "\" text-anchor=\"end\">0</text>\n</svg>\n";
  }
  if (left_out > 0) {
    html += "<p class=\"bad\">" + std::to_string(left_out) +
            " RMS values not finite or negative, left out.</p>\n";
  }
  return html;
}

// The cells as squares and the objects' footprints, seen from above (north up).
std::string top_view(const ReportInput& in) {
  if (in.cells.empty()) return "<p class=\"note\">No cells.</p>\n";
  double xmin = std::numeric_limits<double>::infinity(), ymin = xmin;
  double xmax = -xmin, ymax = -xmin;
  const auto extend = [&](double x, double y) {
    xmin = std::min(xmin, x), xmax = std::max(xmax, x);
    ymin = std::min(ymin, y), ymax = std::max(ymax, y);
  };
  for (const ReportCell& cell : in.cells) {
    extend(cell.bounds[0], cell.bounds[1]);
    extend(cell.bounds[2], cell.bounds[3]);
    for (const ReportObject& object : cell.objects) {
      for (const auto& ring : object.footprint) {
        for (const auto& p : ring) extend(p[0], p[1]);
      }
    }
  }
  const double width = std::max(xmax - xmin, 1e-9), height = std::max(ymax - ymin, 1e-9);
  const double scale = kMapSize / std::max(width, height);
  const auto sx = [&](double x) { return fixed(kMapMargin + (x - xmin) * scale, 2); };
  const auto sy = [&](double y) { return fixed(kMapMargin + (ymax - y) * scale, 2); };
  std::string svg = "<svg width=\"" + fixed(width * scale + 2 * kMapMargin, 0) + "\" height=\"" +
                    fixed(height * scale + 2 * kMapMargin, 0) +
                    "\" role=\"img\" aria-label=\"top view of the cells\">\n";
  for (const ReportCell& cell : in.cells) {
    const auto& b = cell.bounds;
    svg += "<rect class=\"cell\" data-cell=\"" + escape_html(cell.id) + "\" x=\"" + sx(b[0]) +
           "\" y=\"" + sy(b[3]) + "\" width=\"" + fixed((b[2] - b[0]) * scale, 2) + "\" height=\"" +
           fixed((b[3] - b[1]) * scale, 2) + "\"><title>cell " + escape_html(cell.id) + ": " +
           count_of(cell.objects.size(), "object") + "</title></rect>\n";
  }
  for (const ReportCell& cell : in.cells) {
    for (const ReportObject& object : cell.objects) {
      std::string path;
      for (const auto& ring : object.footprint) {
        if (ring.size() < 3) continue;
        for (std::size_t i = 0; i < ring.size(); ++i) {
          path += (i == 0 ? "M" : "L") + sx(ring[i][0]) + " " + sy(ring[i][1]);
        }
        path += "Z";
      }
      if (path.empty()) continue;
      svg += std::string("<path class=\"footprint") + (object.valid ? "" : " invalid") +
             "\" fill-rule=\"evenodd\" d=\"" + path + "\"><title>" + escape_html(object.id) +
             (object.valid ? "" : " (invalid)") + "</title></path>\n";
    }
  }
  for (const ReportCell& cell : in.cells) {
    svg += "<text class=\"label\" x=\"" +
           fixed(kMapMargin + (cell.bounds[0] - xmin) * scale + 4, 2) + "\" y=\"" +
           fixed(kMapMargin + (ymax - cell.bounds[3]) * scale + 14, 2) + "\">" +
           escape_html(cell.id) + "</text>\n";
  }
  svg += "</svg>\n";
  return svg;
}

std::string cells_table(const ReportInput& in, const std::vector<CellGlb>& glbs, bool viewer) {
  std::string html =
      "<table>\n<tr><th>cell</th><th>bounds (m)</th><th class=\"num\">objects</th>"
      "<th class=\"num\">valid</th><th class=\"num\">volume (m³)</th><th>glTF</th>"
      "<th>validation</th></tr>\n";
  for (std::size_t i = 0; i < in.cells.size(); ++i) {
    const ReportCell& cell = in.cells[i];
    std::size_t valid = 0;
    double volume = 0.0;
    for (const ReportObject& object : cell.objects) {
      valid += object.valid ? 1 : 0;
      volume += object.volume;
    }
    const auto& b = cell.bounds;
    html += "<tr><td>" + escape_html(cell.id) + "</td><td>" + fixed(b[0], 1) + ", " +
            fixed(b[1], 1) + " – " + fixed(b[2], 1) + ", " + fixed(b[3], 1) +
            "</td><td class=\"num\">" + std::to_string(cell.objects.size()) +
            "</td><td class=\"num" + (valid < cell.objects.size() ? " bad" : "") + "\">" +
            std::to_string(valid) + "</td><td class=\"num\">" + fixed(volume, 2) + "</td><td>";
    const CellGlb& glb = glbs[i];
    if (!glb.bytes.empty()) {
      html += glb.link.empty() ? std::string(viewer ? "3D view" : "yes")
                               : "<a href=\"" + escape_html(glb.link) + "\">glb</a>";
    } else if (!glb.reason.empty()) {
      html += "<span class=\"bad\">" + escape_html(glb.reason) + "</span>";
    } else {
      html += "<span class=\"note\">none</span>";
    }
    html += "</td><td>";
    for (std::size_t k = 0; k < cell.validation.size(); ++k) {
      html += (k ? "<br>" : "") + escape_html(cell.validation[k]);
    }
    html += "</td></tr>\n";
  }
  html += "</table>\n";
  return html;
}

std::string viewer_section(const ReportInput& in, const std::vector<CellGlb>& glbs, bool viewer) {
  std::string html = "<h2 id=\"view3d\">3D view</h2>\n";
  bool any = false;
  std::string options;
  for (std::size_t i = 0; i < in.cells.size(); ++i) {
    const ReportCell& cell = in.cells[i];
    const std::string id = escape_html(cell.id);
    if (!glbs[i].bytes.empty()) {
      any = true;
      options += "<option value=\"" + id + "\" data-glb-script=\"cells/" + id + ".glb.js\">" + id +
                 " (" + count_of(cell.objects.size(), "object") + ")</option>\n";
    } else {
      const std::string reason = glbs[i].reason.empty() ? "no glTF" : glbs[i].reason;
      options += "<option value=\"" + id + "\" data-reason=\"" + escape_html(reason) + "\">" + id +
                 " (" + escape_html(reason) + ")</option>\n";
    }
  }
  if (!viewer) {
    html +=
        "<p id=\"viewer-status\" class=\"note\">3D view unavailable: this csgtile was built "
        "without its viewer library (three.js from npm; deploy/run-tests.sh installs it before "
        "building).</p>\n";
    return html;
  }
  if (in.cells.empty()) {
    html += "<p id=\"viewer-status\" class=\"note\">No cells.</p>\n";
    return html;
  }
  html += "<p><label>Cell <select id=\"cell-select\">\n" + options + "</select></label></p>\n";
  html += "<div id=\"viewer\"></div>\n<p id=\"viewer-status\">" +
          std::string(any ? "Loading…" : "No cell has a glTF to show.") + "</p>\n";
  return html;
}

// The buildings worst first: those without LoD2.2 (a problem named), then by fit RMS,
// largest first (none known last), then by id; at most kRows rows.
std::string buildings_table(const ReportInput& in) {
  constexpr std::size_t kRows = 100;
  struct Row {
    const ReportObject* object;
    const std::string* cell;
  };
  std::vector<Row> rows;
  for (const ReportCell& cell : in.cells) {
    for (const ReportObject& object : cell.objects) {
      if (object.building) rows.push_back({&object, &cell.id});
    }
  }
  if (rows.empty()) return "<p class=\"note\">No buildings.</p>\n";
  std::stable_sort(rows.begin(), rows.end(), [](const Row& a, const Row& b) {
    const ReportBuilding& x = *a.object->building;
    const ReportBuilding& y = *b.object->building;
    const bool x_full = x.lod == "2.2", y_full = y.lod == "2.2";
    if (x_full != y_full) return !x_full;
    const double xm = x.model_rmse.value_or(-1.0), ym = y.model_rmse.value_or(-1.0);
    if (xm != ym) return xm > ym;
    const double xr = x.fit_rms.value_or(-1.0), yr = y.fit_rms.value_or(-1.0);
    if (xr != yr) return xr > yr;
    return a.object->id < b.object->id;
  });
  std::size_t full = 0;
  for (const Row& r : rows) full += r.object->building->lod == "2.2" ? 1 : 0;
  std::string html = "<p>" + std::to_string(full) + " of " + count_of(rows.size(), "building") +
                     " reached LoD2.2; every building with a block has LoD1.2 too.</p>\n";
  html +=
      "<table class=\"buildings\">\n<tr><th>object</th><th>cell</th><th>LoD</th><th>points to "
      "model: RMSE (m)</th><th>within 2σ</th><th>fit RMS (m)</th><th>fit within 2σ</th><th>ground "
      "(m)</th><th>roof 70% (m)</th><th>roof "
      "surfaces</th><th>footprint</th>"
      "<th>problem</th>"
      "</tr>\n";
  auto metres = [](const std::optional<double>& v) {
    return v && std::isfinite(*v) ? fixed(*v, 2) : std::string("n/a");
  };
  auto share = [](const std::optional<double>& v) {
    return v && std::isfinite(*v) ? fixed(100.0 * *v, 0) + " %" : std::string("n/a");
  };
  for (std::size_t k = 0; k < rows.size() && k < kRows; ++k) {
    const ReportBuilding& b = *rows[k].object->building;
    html += std::string("<tr") + (b.lod == "2.2" ? "" : " class=\"bad\"") + "><td>" +
            escape_html(rows[k].object->id) + "</td><td>" + escape_html(*rows[k].cell) +
            "</td><td>" + escape_html(b.lod.empty() ? "none" : b.lod) + "</td><td class=\"num\">" +
            metres(b.model_rmse) + "</td><td class=\"num\">" + share(b.model_within_2sigma) +
            "</td><td class=\"num\">" + metres(b.fit_rms) + "</td><td class=\"num\">" +
            share(b.fit_within_2sigma) + "</td><td class=\"num\">" + metres(b.h_ground) +
            "</td><td class=\"num\">" + metres(b.h_roof_70p) + "</td><td class=\"num\">" +
            std::to_string(b.roof_surfaces) + "</td><td>" +
            escape_html(b.footprint_id.empty() ? "derived" : b.footprint_id) + "</td><td>" +
            escape_html(b.problem) + "</td></tr>\n";
  }
  html += "</table>\n";
  if (rows.size() > kRows) {
    html += "<p class=\"note\">" + std::to_string(rows.size() - kRows) +
            " more buildings, better ones, are in the GeoPackage (objects: lod, model_rmse, "
            "fit_rms, heights).</p>\n";
  }
  return html;
}

std::string page(const ReportInput& in, const std::vector<CellGlb>& glbs, bool viewer) {
  std::size_t objects = 0, valid = 0;
  for (const ReportCell& cell : in.cells) {
    objects += cell.objects.size();
    for (const ReportObject& object : cell.objects) valid += object.valid ? 1 : 0;
  }
  long long primitives = 0;
  for (const auto& [type, count] : in.primitives_per_type) primitives += count;
  bool any_glb = false;
  for (const CellGlb& glb : glbs) any_glb = any_glb || !glb.bytes.empty();
  const char* state = viewer && any_glb ? "loading" : "unavailable";

  std::string html;
  html += "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n";
  html += "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n";
  html += "<title>csgtile run " + escape_html(in.run) + "</title>\n";
  html += "<link rel=\"stylesheet\" href=\"report.css\">\n</head>\n";
  html += std::string("<body data-viewer=\"") + state + "\">\n";
  html += "<h1>csgtile run " + escape_html(in.run) + "</h1>\n";
  html += "<p class=\"subtitle\">CRS " + escape_html(in.crs.empty() ? "none" : in.crs) +
          " · coordinates in the run frame (metres)</p>\n";

  html += "<div class=\"summary\">\n";
  html += "<div>cells<b>" + std::to_string(in.cells.size()) + "</b></div>\n";
  html += "<div>objects<b>" + std::to_string(objects) + "</b></div>\n";
  html += std::string("<div") + (valid < objects ? " class=\"bad\"" : "") + ">valid objects<b>" +
          std::to_string(valid) + "</b></div>\n";
  html += "<div>primitives<b>" + std::to_string(primitives) + "</b></div>\n";
  html += std::string("<div") + (in.dead_jobs.empty() ? "" : " class=\"bad\"") + ">dead jobs<b>" +
          std::to_string(in.dead_jobs.size()) + "</b></div>\n";
  html += "</div>\n";

  html += "<h2 id=\"top-view\">Cells from above</h2>\n";
  html +=
      "<p class=\"note\">Cell squares and object footprints, north up; invalid objects in "
      "red. Click a cell to show it in the 3D view.</p>\n";
  html += top_view(in);

  html += viewer_section(in, glbs, viewer);

  html += "<h2 id=\"cells\">Cells</h2>\n";
  html += in.cells.empty() ? "<p class=\"note\">No cells.</p>\n" : cells_table(in, glbs, viewer);

  html += "<h2 id=\"objects-per-cell\">Objects per cell</h2>\n";
  if (in.cells.empty()) {
    html += "<p class=\"note\">No cells.</p>\n";
  } else {
    std::vector<std::pair<std::string, double>> rows;
    for (const ReportCell& cell : in.cells) {
      rows.emplace_back(cell.id, static_cast<double>(cell.objects.size()));
    }
    html += bar_chart(rows, "objects per cell", 0);
  }

  html += "<h2 id=\"primitives\">Primitives per type</h2>\n";
  if (in.primitives_per_type.empty()) {
    html += "<p class=\"note\">No primitives.</p>\n";
  } else {
    std::vector<std::pair<std::string, double>> rows;
    for (const auto& [type, count] : in.primitives_per_type) {
      rows.emplace_back(type, static_cast<double>(count));
    }
    html += bar_chart(rows, "primitives per type", 0);
  }

  html += "<h2 id=\"fit\">Fit residuals</h2>\n";
  html += rms_histogram(in.fit_rms);

  html += "<h2 id=\"buildings\">Buildings, worst first</h2>\n";
  html += buildings_table(in);

  html += "<h2 id=\"validation\">Validation</h2>\n";
  if (in.validation_counts.empty()) {
    html += "<p class=\"note\">No validation results.</p>\n";
  } else {
    html += "<table>\n";
    for (const auto& [name, count] : in.validation_counts) {
      html += "<tr><td>" + escape_html(name) + "</td><td class=\"num\">" + std::to_string(count) +
              "</td></tr>\n";
    }
    html += "</table>\n";
  }
  if (in.dead_jobs.empty()) {
    html += "<p>No dead jobs.</p>\n";
  } else {
    html += "<p class=\"bad\">Dead jobs:</p>\n<ul class=\"problems\">\n";
    for (const std::string& job : in.dead_jobs) html += "<li>" + escape_html(job) + "</li>\n";
    html += "</ul>\n";
  }

  html += "<h2 id=\"stage-timings\">Stage timings</h2>\n";
  html +=
      "<div id=\"timings\"><p class=\"note\">Stage timings are drawn by report.js from "
      "timings.js (JavaScript needed).</p></div>\n";

  html += "<p class=\"note\">csgtile " + escape_html(CSGTILE_VERSION);
  if (viewer) {
    html += " · 3D view: " + escape_html(detail::report_viewer_library()) +
            " (MIT licence, bundled in viewer.js)";
  }
  html += "</p>\n";

  // timings.js first: report.js draws what it defines; viewer.js before report.js too.
  html += "<script src=\"timings.js\"></script>\n";
  if (viewer) html += "<script src=\"viewer.js\"></script>\n";
  html += "<script src=\"report.js\"></script>\n</body>\n</html>\n";
  return html;
}

std::string timings_script(const ReportInput& in) {
  nlohmann::json stages = nlohmann::json::array();
  for (const auto& [stage, seconds] : in.stage_seconds) {
    if (std::isfinite(seconds)) stages.push_back({stage, seconds});
  }
  nlohmann::json timings{{"stages", stages}};
  if (!in.peak_job.empty() && std::isfinite(in.peak_rss_mib)) {
    timings["peak"] = {{"job", in.peak_job}, {"mib", in.peak_rss_mib}};
  }
  return "// Stage timings of this run: not deterministic (see report.h).\n"
         "window.csgtileTimings = " +
         timings.dump(-1, ' ', true) + ";\n";
}

}  // namespace

Failure write_run_report(const ReportInput& in, const std::filesystem::path& run_dir,
                         ReportFiles& out) {
  out = {};
  if (Failure f = check_input(in); !f.ok()) return f;
  const bool viewer = !detail::report_viewer_script().empty();

  std::vector<CellGlb> glbs;
  glbs.reserve(in.cells.size());
  for (const ReportCell& cell : in.cells) glbs.push_back(read_glb(cell, run_dir));

  const std::filesystem::path report_dir = run_dir / "report";
  const auto write = [&](const std::string& name, std::string_view bytes,
                         std::vector<std::string>& keys) -> Failure {
    if (Failure f = write_file_atomic(report_dir / name, bytes); !f.ok()) return f;
    keys.push_back("report/" + name);
    return {};
  };
  if (Failure f = write("index.html", page(in, glbs, viewer), out.keys); !f.ok()) return f;
  if (Failure f = write("report.css", detail::report_stylesheet(), out.keys); !f.ok()) return f;
  if (Failure f = write("report.js", detail::report_script(), out.keys); !f.ok()) return f;
  if (viewer) {
    if (Failure f = write("viewer.js", detail::report_viewer_script(), out.keys); !f.ok()) return f;
    for (std::size_t i = 0; i < in.cells.size(); ++i) {
      if (glbs[i].bytes.empty()) continue;
      const std::string id = js_string(in.cells[i].id);
      const std::string script =
          "window.csgtileGlb = window.csgtileGlb || {};\nwindow.csgtileGlb[" + id + "] = \"" +
          base64(glbs[i].bytes) + "\";\n";
      if (Failure f = write("cells/" + in.cells[i].id + ".glb.js", script, out.keys); !f.ok()) {
        return f;
      }
    }
  }
  return write("timings.js", timings_script(in), out.nondeterministic_keys);
}

}  // namespace csgtile::worker
