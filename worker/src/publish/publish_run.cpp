// Publishing a finished run to config.publish.url (see publish_run.h).

#include "publish/publish_run.h"

#include "fetch/input.h"
#include "publish/s3_publish.h"

namespace csgtile::worker::publish {

Failure publish_run_directory(const config::Config& config, const std::filesystem::path& run_dir,
                              const Logger& log, const std::set<std::string>* only) {
  if (config.publish.url.empty()) return {};
  PublishPlan plan;
  if (Failure f = plan_run_directory(run_dir, plan); !f.ok()) return f;
  if (only != nullptr) {
    auto unlisted = [only](const std::string& key) { return only->count(key) == 0; };
    std::erase_if(plan.objects, unlisted);
    std::erase_if(plan.manifests, unlisted);
  }
  PublishReport report;
  if (Failure f = publish_run_to_s3(plan, config.publish.url, config.run.name,
                                    fetch::policy_of(config.fetch), report);
      !f.ok()) {
    return f;
  }
  log.info("publish", report.pointer_changed ? "published" : "already published",
           {{"url", config.publish.url},
            {"pointer", report.pointer_key},
            {"manifest", report.manifest_key},
            {"uploaded", std::to_string(report.uploaded)},
            {"skipped_existing", std::to_string(report.skipped_existing)},
            {"bytes", std::to_string(report.bytes)}});
  return {};
}

}  // namespace csgtile::worker::publish
