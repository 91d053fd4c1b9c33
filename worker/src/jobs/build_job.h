#pragma once
// The "build" job of a run of scene JSON inputs: read the scene, build and check each
// primitive, unify them by its Boolean (a plain set stays a set), publish the native model.

#include <string>

#include "job_context.h"

namespace csgtile::worker::jobs {

/// The build job's runner (job_table.h). Its record names the model, the primitives with
/// their volumes and bounds, the total volume and area, and the topology counts.
Failure run_build_job(const Job& job, const JobContext& context, std::string& result,
                      StageTimings* timings);

}  // namespace csgtile::worker::jobs
