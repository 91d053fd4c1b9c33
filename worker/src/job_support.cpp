// What every job of a run shares (job_support.h).

#include "csgtile/worker/job_support.h"

#include "csgtile/worker/publish.h"

namespace csgtile::worker {

std::string output_config_sha256(const config::Config& config) {
  config::Config hashed = config;
  hashed.run.output.clear();
  hashed.run.threads = 0;
  hashed.queue = {};
  hashed.log = {};
  hashed.metrics = {};
  hashed.fetch = {};
  hashed.publish = {};
  return sha256_hex(config::to_json(hashed));
}

}  // namespace csgtile::worker
