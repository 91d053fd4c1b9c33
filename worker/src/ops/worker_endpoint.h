#pragma once
// Wiring of the ops endpoint (ops_server.h) into `csgtile worker` and `csgtile run`: the listen
// address from --metrics-listen or metrics.listen, liveness after three leases without
// progress, readiness from the stop signal and a queue handle of the endpoint's own.

#include <memory>
#include <optional>
#include <string>

#include "csgtile/config/config.h"
#include "csgtile/worker/log.h"
#include "ops/ops_server.h"

namespace csgtile::worker::ops {

/// Liveness fails after this many lease periods without progress of the work loop.
inline constexpr int kStallLeases = 3;

/// Starts the endpoint when `flag` (--metrics-listen, when given) or else
/// `config.metrics.listen` enables it; returns nullptr with `failure` ok when disabled.
/// Errors: ConfigInvalid (a malformed address, naming the flag or key), Io (cannot bind).
std::unique_ptr<OpsServer> start_worker_endpoint(const config::Config& config,
                                                 const std::optional<std::string>& flag,
                                                 const Logger& log, Failure& failure);

}  // namespace csgtile::worker::ops
