#pragma once
/// \file
/// A whole run on the embedded (SQLite) queue: enqueue one job per input, work the queue
/// until nothing is runnable, publish the run manifest.
///
/// Stages that exist today: read scene (primitives in the scene format) → build solids →
/// check validity → mass properties → publish the native model (content-addressed) and the
/// job's record. LIDAR reading, fitting and assembly join as their issues land.

#include <filesystem>
#include <vector>

#include "csgtile/config/config.h"
#include "csgtile/worker/log.h"
#include "csgtile/worker/queue.h"

namespace csgtile::worker {

struct RunSummary {
  QueueCounts counts;
  std::filesystem::path run_dir;    ///< <run.output>/runs/<run.name>
  std::filesystem::path manifest;   ///< run_dir/manifest.json
  std::vector<DeadJob> dead;
  /// A stop signal ended the run early (after its running job): no index or manifest yet;
  /// running the same config again resumes.
  bool stopped = false;
};

/// Runs `config` to completion on its SQLite queue. Jobs that fail are retried or end dead
/// (their reasons in the summary and the manifest); the run itself fails only when the
/// queue or the output directory cannot be used.
Failure run_embedded(const config::Config& config, const Logger& log, RunSummary& summary);

/// Executes one "build" job: its payload names a scene input. On success `result` is the
/// job's JSON record (deterministic: no timings, no absolute paths).
Failure run_build_job(const Job& job, const std::filesystem::path& run_dir,
                      const config::Config& config, std::string& result);

}  // namespace csgtile::worker
