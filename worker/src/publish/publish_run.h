#pragma once
// Publishing a finished run beyond the local output directory (config `publish.url`).

#include <filesystem>
#include <set>
#include <string>

#include "csgtile/worker/errors.h"
#include "csgtile/worker/log.h"
#include "fetch/fetch.h"

namespace csgtile::worker::publish {

/// Where a run is published and how: the job layer builds it from the config
/// (jobs/export_settings.h).
struct PublishTarget {
  std::string url;       ///< publish.url; empty: the run is not published beyond run.output
  std::string run_name;  ///< run.name: the pointer's and manifests' keys
  fetch::Policy policy;  ///< from the fetch section: retries, timeouts, credentials
};

/// When `target.url` is set, uploads the finished run directory there
/// (s3_publish.h: objects, then create-only manifests, then the pointer) and logs what was
/// uploaded; a no-op otherwise. With `only`, just the files it names (paths relative to the
/// run directory: what the run's manifests list), so that leftovers of an earlier run in the
/// same directory are never published. Errors: as publish_run_to_s3 (Network is retryable).
Failure publish_run_directory(const PublishTarget& target, const std::filesystem::path& run_dir,
                              const Logger& log, const std::set<std::string>* only = nullptr);

}  // namespace csgtile::worker::publish
