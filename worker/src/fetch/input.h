#pragma once
/// \file
/// A run input as a local file: a path is used where it is, a URL (file://, http(s)://,
/// s3://) is fetched into the run's download cache under the config's `fetch:` policy.

#include <cstdint>
#include <filesystem>
#include <string>

#include "csgtile/config/config.h"
#include "csgtile/worker/errors.h"
#include "csgtile/worker/queue.h"
#include "fetch/fetch.h"

namespace csgtile::worker::fetch {

struct LocalInput {
  std::filesystem::path path;
  std::string sha256;  ///< of the content (inputs are identified by it in records)
  std::uint64_t bytes = 0;
  bool fetched = false;  ///< came through the fetcher (else a local path)
  bool from_cache = false;
};

/// The fetch policy of a config.
Policy policy_of(const config::FetchConfig& fetch);

/// Resolves `input` (a path or a URL with an optional #sha256=..&size=.. fragment).
Failure resolve_input(const std::string& input, const config::Config& config, LocalInput& local);

/// The input a job's payload names ({"input": "<path or URL>", ...}) in `input`, resolved as
/// resolve_input does; bytes downloaded are counted in the metrics. Errors: Internal for a
/// malformed payload; as resolve_input.
Failure resolve_job_input(const Job& job, const config::Config& config, std::string& input,
                          LocalInput& local);

}  // namespace csgtile::worker::fetch
