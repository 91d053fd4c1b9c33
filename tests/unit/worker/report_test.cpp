// The run report (export/report.h): the page's figures from a small input, the same bytes for
// the same input with the timings kept in timings.js, a cell whose glTF is missing or not a
// GLB shown without a 3D view, and bad input named. The page itself is opened in headless
// Chromium by tests/cli/report_chromium.py.

#include "export/report.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "csgtile/worker/publish.h"
#include "export/report_assets.h"
#include "export/tile_content.h"
#include "index_object_builder.h"
#include "model_builders.h"
#include "test_support.h"

namespace csgtile::worker {
namespace {

namespace fs = std::filesystem;
using test::read_file;

// A 30 m × 30 m × 8 m house made by the 3D Tiles exporter.
std::string house_glb() {
  auto content = tile_content(
      {test::index_object("house", test::leaf(test::box_at({10, 10, 0}, {30, 30, 8}), "house"))});
  EXPECT_TRUE(content.ok());
  return content.ok() ? content.value().glb : std::string();
}

std::string decode_base64(const std::string& text) {
  const std::string alphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  unsigned bits = 0;
  int count = 0;
  for (char c : text) {
    if (c == '=') break;
    bits = (bits << 6) | static_cast<unsigned>(alphabet.find(c));
    count += 6;
    if (count >= 8) {
      count -= 8;
      out += static_cast<char>((bits >> count) & 0xff);
    }
  }
  return out;
}

// Two cells: "0_0" with a house (valid, a square footprint with a hole) and a shed (invalid),
// its GLB at <run>/tiles/model.glb; "1_0" empty, without a GLB.
ReportInput small_input(const fs::path& run_dir) {
  EXPECT_TRUE(write_file_atomic(run_dir / "tiles" / "model.glb", house_glb()).ok());
  ReportInput in;
  in.run = "demo";
  in.crs = "EPSG:28992+5709";
  ReportCell first;
  first.id = "0_0";
  first.bounds = {0, 0, 100, 100};
  first.glb_path = (run_dir / "tiles" / "model.glb").string();
  first.validation = {"gltf: written", "cityjson: written"};
  first.objects.push_back(
      {"house",
       {"box", "box", "cylinder"},
       1234.5,
       true,
       {{{10, 10}, {40, 10}, {40, 40}, {10, 40}}, {{20, 20}, {30, 20}, {30, 30}, {20, 30}}},
       std::nullopt});
  first.objects.push_back(
      {"shed", {"box"}, 12.0, false, {{{60, 60}, {70, 60}, {70, 70}}}, std::nullopt});
  ReportCell second;
  second.id = "1_0";
  second.bounds = {100, 0, 200, 100};
  in.cells = {first, second};
  in.primitives_per_type = {{"box", 3}, {"cylinder", 1}};
  in.fit_rms = {0.004, 0.006, 0.011, 0.002};
  in.validation_counts = {{"objects valid", 1}, {"objects invalid", 1}};
  in.dead_jobs = {"fit/3: header <bad> & truncated"};
  in.stage_seconds = {{"fit", 12.345678}, {"assemble", 3.25}};
  return in;
}

bool viewer_built() { return !detail::report_viewer_script().empty(); }

TEST(RunReport, PageShowsTheFiguresOfASmallRun) {
  test::TempDir dir("csgtile_report_page_");
  const fs::path run = dir.path() / "run";
  ReportFiles files;
  ASSERT_TRUE(write_run_report(small_input(run), run, files).ok());

  const std::string page = read_file(run / "report" / "index.html");
  ASSERT_FALSE(page.empty());
  EXPECT_NE(page.find("<title>csgtile run demo</title>"), std::string::npos);
  EXPECT_NE(page.find("EPSG:28992+5709"), std::string::npos);
  // Summary: 2 cells, 2 objects, 1 valid, 4 primitives, 1 dead job.
  EXPECT_NE(page.find("cells<b>2</b>"), std::string::npos);
  EXPECT_NE(page.find("objects<b>2</b>"), std::string::npos);
  EXPECT_NE(page.find("valid objects<b>1</b>"), std::string::npos);
  EXPECT_NE(page.find("primitives<b>4</b>"), std::string::npos);
  // Top view: both cells, the house with its hole (two rings, even-odd), the shed invalid.
  EXPECT_NE(page.find("<rect class=\"cell\" data-cell=\"0_0\""), std::string::npos);
  EXPECT_NE(page.find("<rect class=\"cell\" data-cell=\"1_0\""), std::string::npos);
  const auto house = page.find("<title>house</title>");
  ASSERT_NE(house, std::string::npos);
  const std::string house_path = page.substr(page.rfind("<path", house));
  EXPECT_NE(house_path.find("fill-rule=\"evenodd\""), std::string::npos);
  EXPECT_EQ(std::count(house_path.begin(),
                       house_path.begin() + static_cast<long>(house_path.find("<title>")), 'Z'),
            2);
  EXPECT_NE(page.find("<path class=\"footprint invalid\""), std::string::npos);
  EXPECT_NE(page.find("<title>shed (invalid)</title>"), std::string::npos);
  // Charts: objects per cell, primitives per type, the RMS histogram in millimetres.
  EXPECT_NE(page.find("aria-label=\"objects per cell\""), std::string::npos);
  EXPECT_NE(page.find("aria-label=\"primitives per type\""), std::string::npos);
  EXPECT_NE(page.find(">cylinder</text>"), std::string::npos);
  EXPECT_NE(page.find("aria-label=\"fit residual histogram\""), std::string::npos);
  EXPECT_NE(page.find("4 fitted primitives"), std::string::npos);
  EXPECT_NE(page.find("largest 11.00 mm"), std::string::npos);
  // Validation: counts, the cells' own lines, the dead job escaped.
  EXPECT_NE(page.find("<td>objects invalid</td><td class=\"num\">1</td>"), std::string::npos);
  EXPECT_NE(page.find("gltf: written<br>cityjson: written"), std::string::npos);
  EXPECT_NE(page.find("<li>fit/3: header &lt;bad&gt; &amp; truncated</li>"), std::string::npos);
  EXPECT_EQ(page.find("<bad>"), std::string::npos);
  // The GLB inside the run directory is linked relative to the page.
  EXPECT_NE(page.find("href=\"../tiles/model.glb\""), std::string::npos);
  // Timings only in timings.js.
  EXPECT_EQ(page.find("12.345678"), std::string::npos);
  EXPECT_NE(page.find("<script src=\"timings.js\"></script>"), std::string::npos);
  const std::string timings = read_file(run / "report" / "timings.js");
  EXPECT_NE(timings.find(
                "window.csgtileTimings = {\"stages\":[[\"fit\",12.345678],[\"assemble\",3.25]]};"),
            std::string::npos);
  EXPECT_EQ(files.nondeterministic_keys, std::vector<std::string>{"report/timings.js"});
  EXPECT_FALSE(read_file(run / "report" / "report.css").empty());
  EXPECT_NE(read_file(run / "report" / "report.js").find("csgtileTimings"), std::string::npos);

  if (viewer_built()) {
    EXPECT_EQ(files.keys, (std::vector<std::string>{"report/index.html", "report/report.css",
                                                    "report/report.js", "report/viewer.js",
                                                    "report/cells/0_0.glb.js"}));
    EXPECT_NE(page.find("<script src=\"viewer.js\"></script>"), std::string::npos);
    EXPECT_NE(page.find("data-glb-script=\"cells/0_0.glb.js\""), std::string::npos);
    EXPECT_NE(page.find("<option value=\"1_0\" data-reason=\"no glTF\">"), std::string::npos);
    EXPECT_NE(page.find("<body data-viewer=\"loading\">"), std::string::npos);
    EXPECT_NE(read_file(run / "report" / "viewer.js").find("csgtileViewer"), std::string::npos);
    // The cell's script carries the GLB's exact bytes.
    const std::string script = read_file(run / "report" / "cells" / "0_0.glb.js");
    const std::string prefix =
        "window.csgtileGlb = window.csgtileGlb || {};\nwindow.csgtileGlb[\"0_0\"] = \"";
    ASSERT_EQ(script.compare(0, prefix.size(), prefix), 0);
    const std::string encoded = script.substr(prefix.size(), script.size() - prefix.size() - 3);
    EXPECT_EQ(script.substr(script.size() - 3), "\";\n");
    EXPECT_EQ(decode_base64(encoded), read_file(run / "tiles" / "model.glb"));
  } else {
    EXPECT_EQ(files.keys, (std::vector<std::string>{"report/index.html", "report/report.css",
                                                    "report/report.js"}));
    EXPECT_NE(page.find("3D view unavailable"), std::string::npos);
    EXPECT_NE(page.find("<body data-viewer=\"unavailable\">"), std::string::npos);
  }
}

// The report's "Buildings, worst first" section up to its table's end; empty when missing.
std::string buildings_table(const ReportInput& in, const fs::path& run) {
  ReportFiles files;
  if (!write_run_report(in, run, files).ok()) return {};
  const std::string page = read_file(run / "report" / "index.html");
  const auto section = page.find("<h2 id=\"buildings\">Buildings, worst first</h2>");
  if (section == std::string::npos) return {};
  return page.substr(section, page.find("</table>", section) - section);
}

// Buildings worst first: one whose parts did not fuse (LoD1.2 only, its reason shown), then
// by fit RMS, largest first.
TEST(RunReport, BuildingsAreListedWorstFirst) {
  test::TempDir dir("csgtile_report_buildings_");
  const fs::path run = dir.path() / "run";
  ReportInput in = small_input(run);
  ReportBuilding good{"2.2", 0.04, 1.5, 9.25, 2, ""};
  ReportBuilding rough{"2.2", 0.31, 0.5, 12.0, 6, ""};
  ReportBuilding failed{"1.2", 0.02, 0.0, 7.0, 3, "LoD2.2: unsupported: <no pcurve>"};
  good.fit_within_2sigma = 0.934;
  in.cells[0].objects[0].building = good;
  in.cells[0].objects[1].building = rough;
  ReportObject block{"block", {"extrusion"}, 300.0, false, {}, failed};
  in.cells[1].objects.push_back(block);
  const std::string table = buildings_table(in, run);
  ASSERT_FALSE(table.empty());
  EXPECT_NE(table.find("2 of 3 buildings reached LoD2.2"), std::string::npos) << table;
  const auto first = table.find("<td>block</td>");
  const auto second = table.find("<td>shed</td>");
  const auto third = table.find("<td>house</td>");
  ASSERT_NE(first, std::string::npos);
  ASSERT_NE(second, std::string::npos);
  ASSERT_NE(third, std::string::npos);
  EXPECT_LT(first, second);
  EXPECT_LT(second, third);
  EXPECT_NE(table.find("LoD2.2: unsupported: &lt;no pcurve&gt;"), std::string::npos) << table;
  EXPECT_NE(table.find("<td class=\"num\">0.31</td>"), std::string::npos) << table;
  EXPECT_NE(table.find("<td class=\"num\">9.25</td>"), std::string::npos) << table;
  EXPECT_NE(table.find("<td class=\"num\">93 %</td>"), std::string::npos) << table;
}

// Among buildings that reached LoD2.2, the RMSE of all their points to the model ranks them
// (not the fit's own inlier RMS), and both are shown.
TEST(RunReport, BuildingsAreRankedByTheirPointsDistanceToTheModel) {
  test::TempDir dir("csgtile_report_model_fit_");
  const fs::path run = dir.path() / "run";
  ReportInput in = small_input(run);
  ReportBuilding tight_fit{"2.2", 0.02, 1.5, 9.25, 2, ""};  // inliers close, the rest far
  ReportBuilding loose_fit{"2.2", 0.30, 0.5, 12.0, 6, ""};
  tight_fit.model_rmse = 0.87;
  tight_fit.model_within_2sigma = 0.42;
  loose_fit.model_rmse = 0.21;
  in.cells[0].objects[0].building = tight_fit;
  in.cells[0].objects[1].building = loose_fit;
  const std::string table = buildings_table(in, run);
  ASSERT_FALSE(table.empty());
  EXPECT_LT(table.find("<td>house</td>"), table.find("<td>shed</td>")) << table;
  EXPECT_NE(table.find("<th>points to model: RMSE (m)</th>"), std::string::npos) << table;
  EXPECT_NE(table.find("<td class=\"num\">0.87</td><td class=\"num\">42 %</td><td "
                       "class=\"num\">0.02</td>"),
            std::string::npos)
      << table;
}

TEST(RunReport, SameInputGivesSameBytesWhateverTheTimings) {
  test::TempDir dir("csgtile_report_same_");
  ReportFiles first_files, second_files;
  ReportInput first = small_input(dir.path() / "a");
  ASSERT_TRUE(write_run_report(first, dir.path() / "a", first_files).ok());
  ReportInput second = small_input(dir.path() / "b");
  second.stage_seconds = {{"fit", 99.5}, {"assemble", 0.125}, {"index", 1.0}};
  ASSERT_TRUE(write_run_report(second, dir.path() / "b", second_files).ok());

  ASSERT_EQ(first_files.keys, second_files.keys);
  for (const std::string& key : first_files.keys) {
    EXPECT_EQ(read_file(dir.path() / "a" / key), read_file(dir.path() / "b" / key)) << key;
  }
  EXPECT_NE(read_file(dir.path() / "a" / "report" / "timings.js"),
            read_file(dir.path() / "b" / "report" / "timings.js"));
  // Written again over itself: the same bytes.
  const std::string page = read_file(dir.path() / "a" / "report" / "index.html");
  ASSERT_TRUE(write_run_report(first, dir.path() / "a", first_files).ok());
  EXPECT_EQ(read_file(dir.path() / "a" / "report" / "index.html"), page);
}

TEST(RunReport, MissingOrForeignGlbLeavesTheCellWithoutA3dView) {
  test::TempDir dir("csgtile_report_missing_");
  const fs::path run = dir.path() / "run";
  ReportInput in = small_input(run);
  in.cells[0].glb_path = (run / "tiles" / "gone.glb").string();
  in.cells[1].glb_path = (run / "tiles" / "notes.glb").string();
  ASSERT_TRUE(write_file_atomic(run / "tiles" / "notes.glb", "not a glb at all").ok());
  ReportFiles files;
  ASSERT_TRUE(write_run_report(in, run, files).ok());

  const std::string page = read_file(run / "report" / "index.html");
  // The reasons name the files relative to the run directory, not where it happens to be.
  EXPECT_NE(page.find("glTF missing: tiles/gone.glb"), std::string::npos);
  EXPECT_NE(page.find("not a GLB file: tiles/notes.glb"), std::string::npos);
  EXPECT_EQ(page.find(dir.path().string()), std::string::npos);
  EXPECT_FALSE(fs::exists(run / "report" / "cells"));
  EXPECT_NE(page.find("<body data-viewer=\"unavailable\">"), std::string::npos);
  for (const std::string& key : files.keys) EXPECT_EQ(key.find("cells/"), std::string::npos);
}

TEST(RunReport, BadInputIsNamed) {
  test::TempDir dir("csgtile_report_bad_");
  const auto failure = [&](ReportInput in) {
    ReportFiles files;
    return write_run_report(in, dir.path(), files);
  };
  ReportInput in;
  in.cells.push_back({"../escape", {0, 0, 1, 1}, {}, "", {}});
  Failure f = failure(in);
  EXPECT_EQ(f.code, ErrorCode::InputInvalid);
  EXPECT_NE(f.message.find("\"../escape\""), std::string::npos) << f.message;

  in.cells = {{"0_0", {0, 0, 1, 1}, {}, "", {}}, {"0_0", {1, 0, 2, 1}, {}, "", {}}};
  f = failure(in);
  EXPECT_EQ(f.code, ErrorCode::InputInvalid);
  EXPECT_NE(f.message.find("repeated"), std::string::npos) << f.message;

  in.cells = {{"0_0", {0, 0, std::nan(""), 1}, {}, "", {}}};
  f = failure(in);
  EXPECT_EQ(f.code, ErrorCode::InputInvalid);
  EXPECT_NE(f.message.find("bounds"), std::string::npos) << f.message;

  in.cells = {{"0_0",
               {0, 0, 1, 1},
               {{"o",
                 {"box"},
                 1,
                 true,
                 {{{0, 0}, {std::numeric_limits<double>::infinity(), 0}, {0, 1}}},
                 std::nullopt}},
               "",
               {}}};
  f = failure(in);
  EXPECT_EQ(f.code, ErrorCode::InputInvalid);
  EXPECT_NE(f.message.find("object o: footprint"), std::string::npos) << f.message;
  EXPECT_FALSE(fs::exists(dir.path() / "report"));

  // Non-finite residuals and timings are left out, said on the page, never "nan" in a file.
  ReportInput odd;
  odd.fit_rms = {0.01, std::nan(""), -1.0};
  odd.stage_seconds = {{"fit", std::nan("")}};
  ReportFiles files;
  ASSERT_TRUE(write_run_report(odd, dir.path(), files).ok());
  const std::string page = read_file(dir.path() / "report" / "index.html");
  EXPECT_NE(page.find("2 RMS values not finite or negative, left out."), std::string::npos);
  EXPECT_NE(page.find("No cells."), std::string::npos);
  EXPECT_EQ(read_file(dir.path() / "report" / "timings.js").find("nan"), std::string::npos);
}

}  // namespace
}  // namespace csgtile::worker
