// The job kinds and their runners (job_table.h).

#include "jobs/job_table.h"

#include <array>

#include "city/city_jobs.h"
#include "jobs/build_job.h"

namespace csgtile::worker::jobs {

namespace {

// Scene runs: one build job per scene input. City runs (city/city_jobs.h): fit per tile →
// assemble per cell → index per run; a done fit or assemble may let the next stage start.
constexpr std::array<JobKind, 4> kKinds{{
    {"build", &run_build_job, false},
    {"fit", &city::run_fit, true},
    {"assemble", &city::run_assemble, true},
    {"index", &city::run_index, false},
}};

}  // namespace

const JobKind* find_job_kind(std::string_view name) {
  for (const JobKind& kind : kKinds) {
    if (kind.name == name) return &kind;
  }
  return nullptr;
}

Failure run_job(const Job& job, const JobContext& context, std::string& result,
                StageTimings* timings) {
  const JobKind* kind = find_job_kind(job.kind);
  if (kind == nullptr) {
    return {ErrorCode::Internal, "job " + job.key + " has an unknown kind " + job.kind};
  }
  return kind->run(job, context, result, timings);
}

}  // namespace csgtile::worker::jobs
