// The `csgtile synth` driver: options, then scene → truth JSON → (read back) → scan → LAS,
// each output written under a temporary name and renamed into place when complete.

#include <unistd.h>

#include <cmath>
#include <fstream>
#include <string>

#include "csgtile/geo/crs.h"
#include "csgtile/geo/las.h"
#include "csgtile/geo/synth.h"

namespace csgtile::geo {

namespace {

using kernel::Error;
using kernel::ErrorCode;
using kernel::Status;

Status out_of_range(const char* option, double value, const char* range) {
  char text[160];
  std::snprintf(text, sizeof text, "synth option %s = %.17g is not in %s", option, value, range);
  return Error{ErrorCode::InvalidArgument, text};
}

// `name.tmp.<pid>` beside the final file: the rename stays within one file system.
std::filesystem::path temporary_beside(const std::filesystem::path& path) {
  std::filesystem::path tmp = path;
  tmp += ".tmp." + std::to_string(::getpid());
  return tmp;
}

// Removes a temporary file unless it was renamed into place.
class TemporaryFile {
 public:
  explicit TemporaryFile(std::filesystem::path final_path)
      : final_(std::move(final_path)), path_(temporary_beside(final_)) {}
  ~TemporaryFile() {
    if (!committed_) {
      std::error_code ignored;
      std::filesystem::remove(path_, ignored);
    }
  }
  TemporaryFile(const TemporaryFile&) = delete;
  TemporaryFile& operator=(const TemporaryFile&) = delete;

  const std::filesystem::path& path() const { return path_; }
  Status commit() {
    std::error_code ec;
    std::filesystem::rename(path_, final_, ec);
    if (ec) {
      return Error{ErrorCode::IoError, "cannot rename " + path_.string() + " to " +
                                           final_.string() + ": " + ec.message()};
    }
    committed_ = true;
    return {};
  }

 private:
  std::filesystem::path final_;
  std::filesystem::path path_;
  bool committed_ = false;
};

Status write_text(const std::filesystem::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) return Error{ErrorCode::IoError, "cannot create " + path.string()};
  out.write(text.data(), static_cast<std::streamsize>(text.size()));
  out.close();
  if (!out) return Error{ErrorCode::IoError, "cannot write " + path.string()};
  return {};
}

}  // namespace

Status SynthOptions::validate() const {
  auto bad = [](double v, double lo, double hi) {
    return !(std::isfinite(v) && v >= lo && v <= hi);
  };
  if (points < 1 || points > 4000000000ULL) {
    return out_of_range("points", static_cast<double>(points), "[1, 4e9]");
  }
  if (bad(noise_sigma, 0.0, 10.0)) return out_of_range("noise", noise_sigma, "[0, 10] m");
  if (bad(outlier_fraction, 0.0, 1.0)) {
    return out_of_range("outliers", outlier_fraction, "[0, 1]");
  }
  if (bad(altitude, 10.0, 10000.0)) return out_of_range("altitude", altitude, "[10, 10000] m");
  if (bad(scan_angle_deg, 1e-3, 75.0)) {
    return out_of_range("scan-angle", scan_angle_deg, "(0, 75] degrees");
  }
  if (strips < 1 || strips > 100) return out_of_range("strips", strips, "[1, 100]");
  if (bad(margin, 0.0, 1000.0)) return out_of_range("margin", margin, "[0, 1000] m");
  if (stations < 1 || stations > 64) return out_of_range("stations", stations, "[1, 64]");
  if (bad(station_height, 0.1, 100.0)) {
    return out_of_range("station-height", station_height, "[0.1, 100] m");
  }
  if (bad(max_range, 1.0, 10000.0)) return out_of_range("max-range", max_range, "[1, 10000] m");
  if (bad(min_elevation_deg, -89.0, 80.0)) {
    return out_of_range("min-elevation", min_elevation_deg, "[-89, 80] degrees");
  }
  if (point_format != 6 && point_format != 7) {
    return out_of_range("point-format", point_format, "{6, 7}");
  }
  for (double v : origin) {
    if (!std::isfinite(v)) return Error{ErrorCode::InvalidArgument, "synth origin is not finite"};
  }
  return {};
}

kernel::Result<SynthSummary> synthesize(const SynthOptions& options,
                                        const std::filesystem::path& las_path,
                                        const std::filesystem::path& truth_path) {
  if (auto status = options.validate(); !status.ok()) return status.error();
  if (las_path == truth_path) {
    return Error{ErrorCode::InvalidArgument, "the LAS and truth outputs are the same file"};
  }
  auto crs = crs_from_config(options.crs);
  if (!crs.ok()) return crs.error();
  auto made = make_synth_scene(options.scene, options.seed, options.random_primitives);
  if (!made.ok()) return made.error();
  SynthScene scene = std::move(made).value();
  scene.scene.frame = SceneFrame{options.crs, options.origin};

  // Scan the truth as it reads back, so that the file describes exactly what was scanned.
  const std::string truth_text = scene_to_json(scene.scene);
  auto reread = parse_scene(truth_text);
  if (!reread.ok()) {
    return Error{ErrorCode::InvalidArgument,
                 "synth scene does not read back: " + reread.error().message};
  }
  scene.scene = std::move(reread).value();

  TemporaryFile truth_file(truth_path);
  if (auto s = write_text(truth_file.path(), truth_text); !s.ok()) return s.error();

  LasWriteOptions las;
  las.version_minor = 4;
  las.point_format = options.point_format;
  las.scale = {0.001, 0.001, 0.001};
  las.offset = options.origin;
  las.extra = *synth_extra_layout();
  las.wkt = crs_to_wkt1(crs.value());
  las.global_encoding = 1;  // GPS time is adjusted standard GPS time
  las.generating_software = "csgtile synth";
  las.system_identifier =
      ("synth " + options.scene + " seed " + std::to_string(options.seed)).substr(0, 32);
  TemporaryFile las_file(las_path);
  auto writer = LasWriter::create(las_file.path(), las);
  if (!writer.ok()) return writer.error();
  LasWriter& w = *writer.value();
  auto summary =
      scan_scene(scene, options, [&w](const PointBatch& batch) { return w.write(batch); });
  if (!summary.ok()) return summary.error();
  if (auto s = w.close(); !s.ok()) return s.error();
  if (auto s = truth_file.commit(); !s.ok()) return s.error();
  if (auto s = las_file.commit(); !s.ok()) return s.error();
  return summary;
}

}  // namespace csgtile::geo
