// Publishing a finished run to publish.url (see publish_run.h).

#include "publish/publish_run.h"

#include "publish/s3_publish.h"

namespace csgtile::worker::publish {

Failure publish_run_directory(const PublishTarget& target, const std::filesystem::path& run_dir,
                              const Logger& log, const std::set<std::string>* only) {
  if (target.url.empty()) return {};
  PublishPlan plan;
  if (Failure f = plan_run_directory(run_dir, plan); !f.ok()) return f;
  if (only != nullptr) {
    auto unlisted = [only](const std::string& key) { return only->count(key) == 0; };
    std::erase_if(plan.objects, unlisted);
    std::erase_if(plan.manifests, unlisted);
  }
  PublishReport report;
  if (Failure f = publish_run_to_s3(plan, target.url, target.run_name, target.policy, report);
      !f.ok()) {
    return f;
  }
  log.info("publish", report.pointer_changed ? "published" : "already published",
           {{"url", target.url},
            {"pointer", report.pointer_key},
            {"manifest", report.manifest_key},
            {"uploaded", std::to_string(report.uploaded)},
            {"skipped_existing", std::to_string(report.skipped_existing)},
            {"bytes", std::to_string(report.bytes)}});
  return {};
}

}  // namespace csgtile::worker::publish
