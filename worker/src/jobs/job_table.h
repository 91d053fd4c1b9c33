#pragma once
// The job layer (issue #23): every kind of job a queue holds, with the one runner that executes
// it, each handed the same context built once by the work loop. The work loop (run.cpp) looks a
// job's kind up here and never names a kind itself; the jobs never include the loop's header.

#include <string>
#include <string_view>

#include "job_context.h"

namespace csgtile::worker::jobs {

struct JobKind {
  std::string_view name;  ///< the queue's kind column: "build", "fit", "assemble", "index"
  JobRunner run = nullptr;
  /// Whether a job of this kind, once done, may let the next stage of a city run start.
  bool advances_city_run = false;
};

/// The kind named `name`; nullptr when no job has that kind.
const JobKind* find_job_kind(std::string_view name);

/// Runs `job` by its kind's runner; an unknown kind is an Internal failure naming it.
Failure run_job(const Job& job, const JobContext& context, std::string& result,
                StageTimings* timings);

}  // namespace csgtile::worker::jobs
