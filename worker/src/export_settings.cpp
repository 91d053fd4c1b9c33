// The exporters' settings from a run's configuration (export_settings.h).

#include "export_settings.h"

#include "csgtile/worker/job_support.h"
#include "fetch/input.h"

namespace csgtile::worker::jobs {

RunExportOptions export_options(const config::Config& config) {
  RunExportOptions options;
  options.chordal_tolerance = config.kernel.chordal_tolerance;
  options.linear_tolerance = config.kernel.linear_tolerance;
  options.threads = config.run.threads;
  return options;
}

ManifestIdentity manifest_identity(const config::Config& config) {
  return ManifestIdentity{config.run.name, output_config_sha256(config), config.run.seed};
}

publish::PublishTarget publish_target(const config::Config& config) {
  return publish::PublishTarget{config.publish.url, config.run.name,
                                fetch::policy_of(config.fetch)};
}

RunJobs run_jobs(const config::Config& config) {
  return RunJobs{config.run.name, config.run.inputs};
}

}  // namespace csgtile::worker::jobs
