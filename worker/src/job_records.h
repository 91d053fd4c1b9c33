#pragma once
// A done job's record as the queue keeps it: its deterministic result plus "timings" (stage
// seconds, total, worker, attempt). Manifests carry the result; the timings go to the run's
// timings.json, so that manifest.json stays byte-identical from run to run.

#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include <vector>

#include "csgtile/worker/errors.h"
#include "csgtile/worker/job_support.h"
#include "csgtile/worker/queue.h"

namespace csgtile::worker {

/// A job's timings: {"stages", "seconds", "worker" (unless empty), "attempt", "peak_rss_mib"
/// (when known)}.
nlohmann::ordered_json timings_json(const StageTimings& timings, double seconds,
                                    const std::string& worker_id, int attempt,
                                    std::optional<double> peak_rss_mib);

/// `result` (a JSON object) with "timings" added (and the job's peak resident memory in MiB
/// when known); other text is returned unchanged.
std::string with_timings(const std::string& result, const StageTimings& timings, double seconds,
                         const std::string& worker_id, int attempt,
                         std::optional<double> peak_rss_mib = std::nullopt);

/// Accumulates done jobs' records: manifest entries {"key", "result"} without timings, and
/// timings.json entries {"key", "stages", "seconds", "worker", "attempt", "peak_rss_mib"}.
struct JobRecords {
  nlohmann::ordered_json jobs = nlohmann::ordered_json::array();
  nlohmann::ordered_json timings = nlohmann::ordered_json::array();
  void add(const std::string& key, nlohmann::ordered_json record);
};

/// Whether a queue key "<kind>:<run>:..." belongs to `run` (run names have no ':'): a queue
/// may hold several runs' jobs.
bool is_job_of_run(const std::string& key, const std::string& run);

/// The manifest's "dead" list: {"key", "attempts", "error"} per dead job, in the given order.
nlohmann::ordered_json dead_jobs_json(const std::vector<DeadJob>& dead);

/// Writes run_dir/timings.json (atomically) from the records' timings. Error: Io.
Failure write_timings(const std::filesystem::path& run_dir, const std::string& run,
                      const JobRecords& records);

}  // namespace csgtile::worker
