#pragma once
// Shared pieces of the city jobs (city_jobs.h): the cell grid, files and records.

#include <array>
#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <stop_token>
#include <string>
#include <utility>
#include <vector>

#include "csgtile/config/config.h"
#include "csgtile/kernel/bounding_box.h"
#include "csgtile/kernel/csg.h"
#include "csgtile/kernel/grid.h"
#include "csgtile/kernel/primitives.h"
#include "csgtile/worker/errors.h"
#include "csgtile/worker/files.h"
#include "csgtile/worker/job_support.h"
#include "csgtile/worker/log.h"
#include "csgtile/worker/queue.h"

namespace csgtile::worker::city::detail {

using nlohmann::ordered_json;

/// The run's grid (kernel/grid.h): squares of city.cell_size aligned to multiples of it, with
/// city.halo. Every decision about which cell an anchor is in goes through its cell_of, so that
/// all jobs agree bit for bit; an object's cell is the least (GridCell's order) of its
/// primitives' anchor cells, which every one of them had an assemble job for.
kernel::Grid run_grid(const config::Config& config);

/// Cells first..last (columns and rows) of the run's grid: a block of a LAS/LAZ tile over
/// city.split_points, fitted by one job (a COPC cell is a block of one cell).
struct CellBlock {
  kernel::GridCell first;
  kernel::GridCell last;
  /// "<first cell>-<last cell>", as job keys and fit records name it.
  std::string name() const;
  /// [first column, first row, last column, last row], as tiles.json and fit payloads hold it.
  std::array<std::int64_t, 4> corners() const;
  /// The square its cells cover, CRS coordinates: [xmin, ymin, xmax, ymax].
  std::array<double, 4> extent(const kernel::Grid& grid) const;
  /// From corners() (integers, first ≤ last in each axis); nullopt for anything else.
  static std::optional<CellBlock> parse(const nlohmann::json& corners);
};

/// The box in CRS coordinates of a primitive read from a fit's scene file (tile `origin`
/// added), or an empty box when it cannot be built. The fit job (on its scene file's parsed
/// text) and the assemble jobs compute anchors with this one function from the same bytes,
/// so they agree bit for bit.
kernel::BoundingBox primitive_crs_box(const kernel::PrimitiveSpec& spec, const kernel::Vec3& origin,
                                      double tolerance);

/// Content-addressed files of one job, written together by commit() (write_files_atomic:
/// one directory flush for all of them). A key already published, or already in the batch,
/// is skipped: its name is its hash, so it holds these bytes.
class ObjectBatch {
 public:
  explicit ObjectBatch(std::filesystem::path run_dir) : run_dir_(std::move(run_dir)) {}
  /// Error: Internal for an unsafe key.
  Failure add(const std::string& key, std::string bytes);
  /// Error: Io, naming the file.
  Failure commit();

 private:
  std::filesystem::path run_dir_;
  std::set<std::string> keys_;
  std::vector<std::pair<std::filesystem::path, std::string>> files_;
};
/// Writes one content-addressed file unless it exists (a batch of one). Error: Internal for
/// an unsafe key, Io.
Failure publish_object(const std::filesystem::path& run_dir, const std::string& key,
                       const std::string& bytes);
/// A native model published under objects/ by its content: its key, hash and size.
struct PublishedModel {
  std::string key, sha256;
  std::size_t bytes = 0;
};
/// Adds `model` in the native format as objects/<sha256>.csgt to `batch`.
Failure publish_model(const kernel::CsgModel& model, ObjectBatch& batch, PublishedModel& out);
/// The same for a model already written in the native format (`bytes`).
Failure publish_native(std::string bytes, ObjectBatch& batch, PublishedModel& out);
/// {"key", "sha256", "bytes"} of a file written under `dir` (read back and hashed).
Failure describe_file(const std::filesystem::path& dir, const std::string& key, ordered_json& out);

/// Records of done jobs of `config`'s run whose key starts with "<kind>:<run>:", by key.
std::vector<std::pair<std::string, ordered_json>> done_records(
    const std::vector<std::pair<std::string, std::string>>& results, const std::string& kind,
    const std::string& run);

// `stop`: the job's stop token (jobs::JobContext): its fit and assembly return Cancelled once
// asked.
Failure run_fit_job(const Job& job, const std::filesystem::path& run_dir,
                    const config::Config& config, std::string& result, StageTimings* timings,
                    std::stop_token stop);
Failure run_assemble_job(const Job& job, const std::filesystem::path& run_dir,
                         const config::Config& config, std::string& result, StageTimings* timings,
                         std::stop_token stop);
Failure run_index_job(const Job& job, const std::filesystem::path& run_dir,
                      const config::Config& config, JobQueue& queue, const Logger& log,
                      std::string& result, StageTimings* timings);

}  // namespace csgtile::worker::city::detail
