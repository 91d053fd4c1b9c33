#pragma once
// What the job layer hands every job's runner (jobs/job_table.h): one context built once by the
// work loop. Below both the job table and the jobs it runs (city/, jobs/build_job), so neither
// includes the other for it.

#include <filesystem>
#include <stop_token>
#include <string>

#include "csgtile/config/config.h"
#include "csgtile/worker/job_support.h"
#include "csgtile/worker/log.h"
#include "csgtile/worker/queue.h"

namespace csgtile::worker::jobs {

/// What every runner is handed: where the run's outputs go, the run's config (tolerances,
/// threads, seed), its queue (the index job reads the run's other records), the logger, and
/// the stop token a worker shutting down asks (Booleans, assembly and fit then return
/// Cancelled at their next step).
struct JobContext {
  const std::filesystem::path& run_dir;
  const config::Config& config;
  JobQueue& queue;
  const Logger& log;
  std::stop_token stop;
};

/// Executes one job. On success `result` is its deterministic JSON record; `timings`, when
/// given, receives the seconds of each stage that ran (also on failure).
using JobRunner = Failure (*)(const Job& job, const JobContext& context, std::string& result,
                              StageTimings* timings);

}  // namespace csgtile::worker::jobs
