#pragma once
/// \file
/// The run report: one static HTML page per run (issue #9 item 6) with the figures people
/// look at rather than read — objects per cell, primitives per type, a fit residual (RMS)
/// histogram, the buildings worst first (no LoD2.2, then the largest fit RMS), validation
/// results, dead jobs, stage timings — a top view of the cells with
/// the objects' footprints, and an interactive 3D view of each cell's glTF.
///
/// The page works opened from file:// with no network: everything it uses is written beside
/// it, and data reaches it through <script> elements (Chromium refuses fetch() of file://
/// URLs). Files, under <run_dir>/report/:
///
/// | file                | what                                              | deterministic  |
/// |---------------------|---------------------------------------------------|----------------|
/// | index.html          | the page: tables and SVG charts, made here        | yes            |
/// | report.css          | csgtile's own style (compiled in)                 | yes, per build |
/// | report.js           | csgtile's own page script (compiled in)           | yes, per build |
/// | viewer.js           | three.js + loader + controls + glue (compiled in) | yes, per build |
/// | cells/<cell>.glb.js | a cell's GLB as base64 (cells with a GLB)         | yes            |
/// | timings.js          | the stage timings                                 | no             |
///
/// viewer.js and the cells' scripts are written only by a build with the 3D view
/// (report_assets/embed.cmake: three and esbuild from npm at configure time); without it
/// the page says that the 3D view is unavailable.
///
/// The same input gives the same bytes in every file but timings.js, which is always
/// written (an empty list when there are no timings) so the page never requests a missing
/// file.
///
/// Internal API of the worker (the run's "index" job); not installed.

#include <array>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "csgtile/worker/errors.h"

namespace csgtile::worker {

/// A building's figures (issue #18 item 6): objects with a LoD1.2 block or a reason for none.
struct ReportBuilding {
  std::string lod;                ///< the LoD reached: "2.2", "1.2", or empty (neither)
  std::optional<double> fit_rms;  ///< metres, inlier-weighted over its fitted primitives
  std::optional<double> h_ground, h_roof_70p;  ///< heights in the CRS (metres)
  long long roof_surfaces = 0;
  std::string problem;         ///< why LoD2.2 or LoD1.2 is missing; empty when neither is
  std::string footprint_id{};  ///< the footprint it stands on; empty: outline derived
  std::optional<double> fit_within_2sigma{};  ///< share of its fitted points within 2σ
  /// All of its points against its model (IndexObject::model_fit): RMS distance (metres) and
  /// share within 2σ; buildings are ranked by it when present.
  std::optional<double> model_rmse{};
  std::optional<double> model_within_2sigma{};
};

struct ReportObject {
  std::string id;
  std::vector<std::string> primitive_types;  ///< one entry per primitive ("box", "cylinder", …)
  double volume = 0.0;                       ///< cubic metres; non-finite shows as "n/a"
  bool valid = false;
  /// Footprint rings in the run frame (metres, x east, y north), outer and holes alike
  /// (drawn even-odd); may be empty.
  std::vector<std::vector<std::array<double, 2>>> footprint;
  std::optional<ReportBuilding> building;  ///< set for buildings
};

struct ReportCell {
  std::string id;                  ///< e.g. "3_-1"; [A-Za-z0-9._-] only (it names a file)
  std::array<double, 4> bounds{};  ///< xmin, ymin, xmax, ymax in the run frame (metres)
  std::vector<ReportObject> objects;
  /// The cell's GLB file (any path), or empty when the cell has none.
  std::string glb_path;
  std::vector<std::string> validation;  ///< e.g. "gltf: written", problems found
};

struct ReportInput {
  std::string run;
  std::string crs;
  std::vector<ReportCell> cells;  ///< shown in this order
  std::map<std::string, long long> primitives_per_type;
  std::vector<double> fit_rms;  ///< metres, one per fitted primitive (non-finite left out, counted)
  std::vector<std::pair<std::string, long long>> validation_counts;  ///< e.g. {"objects valid", 12}
  std::vector<std::string> dead_jobs;                                ///< "key: reason"
  /// Seconds per stage, in order. Not deterministic: written to report/timings.js only.
  std::vector<std::pair<std::string, double>> stage_seconds;
  /// The job whose process reached the highest resident memory while it ran, and that peak in
  /// MiB (timings.json's peak_rss_mib); empty when none was recorded. Not deterministic either.
  std::string peak_job = {};
  double peak_rss_mib = 0.0;
};

struct ReportFiles {
  /// Written files whose bytes depend only on the input (and the csgtile build), relative to
  /// the run directory, in a fixed order ("report/index.html" first).
  std::vector<std::string> keys;
  /// Written files that differ between runs of the same input: "report/timings.js".
  std::vector<std::string> nondeterministic_keys;
};

/// Writes the run report under `run_dir`/report/ (each file with write_file_atomic) and
/// lists the written files in `out` (cleared first).
///
/// A cell whose glb_path names a file that cannot be read does not fail the report: the
/// cell is shown without a 3D view, with the reason on the page (a report exists to show
/// problems). Errors: InputInvalid (a cell id empty, repeated or not [A-Za-z0-9._-]; non-finite
/// or inverted cell bounds; a non-finite footprint point), Io (a file cannot be written).
/// Complexity: linear in the input plus the GLB sizes.
Failure write_run_report(const ReportInput& in, const std::filesystem::path& run_dir,
                         ReportFiles& out);

}  // namespace csgtile::worker
