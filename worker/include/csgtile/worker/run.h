#pragma once
/// \file
/// A run on a job queue (SQLite or PostgreSQL): enqueue its jobs, work the queue (one
/// process, or many workers sharing it), publish the run's outputs and manifest.
///
/// Two kinds of run. A run of LIDAR tiles is a city: fit per tile → assemble per cell →
/// index per run (worker/src/city/city_jobs.h; its index job publishes). A run of scene JSON
/// inputs builds each scene (read → build solids → check → Booleans → native model) in a
/// "build" job and publish_run writes its exports once the queue is drained.

#include <chrono>
#include <filesystem>
#include <functional>
#include <stop_token>
#include <string>
#include <utility>
#include <vector>

#include "csgtile/config/config.h"
#include "csgtile/worker/job_support.h"
#include "csgtile/worker/log.h"
#include "csgtile/worker/queue.h"

namespace csgtile::worker {

struct RunSummary {
  QueueCounts counts;
  std::filesystem::path run_dir;   ///< <run.output>/runs/<run.name>
  std::filesystem::path manifest;  ///< run_dir/manifest.json
  std::vector<DeadJob> dead;
  /// A stop signal ended the run early (after its running job): no index or manifest yet;
  /// running the same config again resumes.
  bool stopped = false;
  /// The job the stop cancelled and released to the queue ("" when none was cut short), and
  /// whether the release succeeded (else its lease expires).
  std::string released_job{};
  bool released = false;
};

/// Called just before a stopped worker ends the process because its job outlasted the grace
/// period and did not return when asked to stop (a step that does not look at the stop
/// token: the job is released to the queue): the job's key and whether the release
/// succeeded. The command prints its summary here; nothing after it runs. A job that returns
/// Cancelled is released the same way and the worker returns through main instead
/// (WorkSummary::released_job).
using ForcedExitReport = std::function<void(const std::string& job, bool released)>;

/// Runs `config` to completion on its SQLite queue. Jobs that fail are retried or end dead
/// (their reasons in the summary and the manifest); the run itself fails only when the
/// queue or the output directory cannot be used.
Failure run_embedded(const config::Config& config, const Logger& log, RunSummary& summary,
                     const ForcedExitReport& on_forced_exit = {});

/// Adds one build job per input of `config` (a no-op for jobs already in the queue);
/// `added` counts the new ones.
Failure enqueue_run(const config::Config& config, JobQueue& queue, const Logger& log,
                    std::size_t& added);

struct WorkOptions {
  bool exit_when_idle = false;          ///< return once the queue has no unfinished job
  std::chrono::milliseconds poll{100};  ///< wait between claims when nothing is runnable
  std::string worker_id;                ///< default "local-<pid>"
  ForcedExitReport on_forced_exit;      ///< may be empty
};

struct WorkSummary {
  long long jobs = 0;     ///< jobs this worker ran (any outcome)
  bool finished = false;  ///< the queue had no unfinished job when last looked at
  bool stopped = false;   ///< a stop signal ended the loop
  /// The job the stop cancelled at the end of the grace period and released ("" if none),
  /// and whether the release succeeded.
  std::string released_job{};
  bool released = false;
};

/// Claims and runs jobs (lease heartbeat, fencing, retries) until a stop signal, or — with
/// exit_when_idle — until the queue has no unfinished job.
Failure work_queue(const config::Config& config, JobQueue& queue, const Logger& log,
                   const WorkOptions& options, WorkSummary& work);

/// Publishes the run from the queue's done jobs: topology index, CityJSONSeq, 3D Tiles, then
/// the manifest naming them. Deterministic, so publishing twice writes the same bytes.
Failure publish_run(const config::Config& config, JobQueue& queue, const Logger& log,
                    RunSummary& summary);

}  // namespace csgtile::worker
