#pragma once
// What the exporters, the manifests and the publisher take from a run's configuration, built
// in this one place by the jobs that write outputs: the writers themselves never see the
// config (issue #23).

#include "csgtile/config/config.h"
#include "export/manifest.h"
#include "export/run_index.h"
#include "publish/publish_run.h"

namespace csgtile::worker::jobs {

/// kernel.chordal_tolerance, kernel.linear_tolerance, run.threads.
RunExportOptions export_options(const config::Config& config);
/// run.name, the outputs' config hash (job_support.h), run.seed.
ManifestIdentity manifest_identity(const config::Config& config);
/// publish.url, run.name and the fetch section's policy.
publish::PublishTarget publish_target(const config::Config& config);
/// run.name and run.inputs: the build jobs of a scene run.
RunJobs run_jobs(const config::Config& config);

}  // namespace csgtile::worker::jobs
