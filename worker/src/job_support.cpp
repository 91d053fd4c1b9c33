// What every job of a run shares (job_support.h).

#include "csgtile/worker/job_support.h"

#include <nlohmann/json.hpp>

#include "csgtile/worker/publish.h"

namespace csgtile::worker {

std::string output_config_sha256(const config::Config& config) {
  // The sections that do not shape outputs are left out of the hashed text altogether (not
  // reset to their defaults), so that a key added to them later changes no manifest's hash.
  nlohmann::json hashed = nlohmann::json::parse(config::to_json(config));
  for (const char* section : {"queue", "log", "metrics", "fetch", "publish"}) hashed.erase(section);
  hashed["run"].erase("output");
  hashed["run"].erase("threads");
  return sha256_hex(hashed.dump());
}

}  // namespace csgtile::worker
