#include "ops/worker_endpoint.h"

#include <mutex>

#include "csgtile/worker/queue.h"
#include "stop_signal.h"

namespace csgtile::worker::ops {

namespace {

/// The endpoint's own queue handle, opened on first use and reopened after a failure, so a
/// scrape never waits on the work loop's handle (nor the loop on a scrape).
class QueueProbe {
 public:
  explicit QueueProbe(config::Config config) : config_(std::move(config)) {}
  Failure counts(QueueCounts& out) {
    const std::lock_guard lock(mutex_);
    Failure failure;
    if (!queue_) queue_ = open_queue(config_, failure);
    if (!queue_) return failure;
    out = queue_->counts(failure);
    if (!failure.ok()) queue_.reset();
    return failure;
  }

 private:
  const config::Config config_;
  std::mutex mutex_;
  std::unique_ptr<JobQueue> queue_;
};

}  // namespace

std::unique_ptr<OpsServer> start_worker_endpoint(const config::Config& config,
                                                 const std::optional<std::string>& flag,
                                                 const Logger& log, Failure& failure) {
  OpsOptions options;
  failure = parse_listen_address(flag ? *flag : config.metrics.listen,
                                 flag ? "--metrics-listen" : "metrics.listen", options.listen);
  if (!failure.ok() || !options.listen.enabled) return nullptr;
  options.stall_after =
      std::chrono::seconds(std::int64_t{kStallLeases} * config.queue.lease_seconds);
  options.draining = [] { return stop_requested(); };
  auto probe = std::make_shared<QueueProbe>(config);
  options.queue_counts = [probe](QueueCounts& counts) { return probe->counts(counts); };
  options.version = CSGTILE_VERSION;
  metrics();  // constructed now: process_start_time_seconds and liveness count from here
  auto server = OpsServer::start(std::move(options), failure);
  if (server) {
    log.info("metrics", "listening",
             {{"address", server->address()}, {"paths", "/healthz /readyz /metrics"}});
  }
  return server;
}

}  // namespace csgtile::worker::ops
