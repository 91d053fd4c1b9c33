#pragma once
/// \file
/// What every job of a run shares, below the queue loop that runs them (run.h): the wall time
/// of its stages, and the hash of the settings its outputs depend on, which every manifest
/// records. The jobs include this, never run.h.

#include <string>
#include <utility>
#include <vector>

#include "csgtile/config/config.h"

namespace csgtile::worker {

/// Wall time of each stage of one job ("fetch", "read", "build", "check", "boolean",
/// "publish"), in the order the stages first ran. Not deterministic: kept out of the run's
/// manifest.json and published in timings.json beside it.
struct StageTimings {
  std::vector<std::pair<std::string, double>> seconds;
};

/// SHA-256 of the settings that shape a run's outputs, as manifests record it: the config's
/// canonical JSON without where outputs and the queue are (run.output, queue), how many
/// threads work (outputs do not depend on it), logging, metrics, fetching and publishing —
/// those keys are not in the hashed text at all, so adding one changes no hash.
std::string output_config_sha256(const config::Config& config);

}  // namespace csgtile::worker
