#include "fetch/input.h"

#include <nlohmann/json.hpp>

#include "csgtile/worker/files.h"
#include "ops/metrics.h"

namespace csgtile::worker::fetch {

Policy policy_of(const config::FetchConfig& fetch) {
  Policy policy;
  policy.schemes = fetch.schemes;
  policy.connect_timeout_ms = 1000L * fetch.connect_timeout_seconds;
  policy.transfer_timeout_ms = 1000L * fetch.timeout_seconds;
  policy.low_speed_bytes_per_second = fetch.low_speed_bytes_per_second;
  policy.low_speed_seconds = fetch.low_speed_bytes_per_second > 0 ? fetch.low_speed_seconds : 0;
  policy.max_bytes = fetch.max_bytes;
  policy.max_redirects = fetch.max_redirects;
  policy.attempts = fetch.attempts;
  policy.ca_bundle = fetch.ca_bundle;
  policy.s3.endpoint = fetch.s3_endpoint;
  policy.s3.region = fetch.s3_region;
  return policy;
}

Failure resolve_input(const std::string& input, const config::Config& config, LocalInput& local) {
  local = {};
  if (!is_url(input)) {
    // An unreadable path is left to the reader, whose message names the file and the cause.
    local.path = input;
    if (!file_sha256(local.path, local.sha256, local.bytes).ok()) local.sha256.clear();
    return {};
  }
  Request request;
  if (Failure f = parse_request(input, request); !f.ok()) return f;
  const std::filesystem::path cache = config.fetch.cache_dir.empty()
                                          ? std::filesystem::path(config.run.output) / "cache"
                                          : std::filesystem::path(config.fetch.cache_dir);
  Result result;
  if (Failure f = fetch(request, policy_of(config.fetch), cache, result); !f.ok()) return f;
  local.path = result.path;
  local.sha256 = result.sha256;
  local.bytes = result.bytes;
  local.fetched = true;
  local.from_cache = result.from_cache;
  return {};
}

Failure resolve_job_input(const Job& job, const config::Config& config, std::string& input,
                          LocalInput& local) {
  const auto payload = nlohmann::json::parse(job.payload, nullptr, false);
  if (payload.is_discarded() || !payload.contains("input") || !payload["input"].is_string()) {
    return {ErrorCode::Internal, "job " + job.key + " has a malformed payload"};
  }
  input = payload["input"].get<std::string>();
  if (Failure f = resolve_input(input, config, local); !f.ok()) return f;
  if (local.fetched && !local.from_cache) ops::metrics().add_bytes_fetched(local.bytes);
  return {};
}

}  // namespace csgtile::worker::fetch
