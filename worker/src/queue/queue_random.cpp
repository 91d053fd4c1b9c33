#include "queue/queue_random.h"

#include <algorithm>
#include <cmath>

namespace csgtile::worker::detail {

std::string QueueRandom::lease_token(const std::string& worker_id, std::int64_t now_ms) {
  return worker_id + "-" + std::to_string(now_ms) + "-" + std::to_string(engine_());
}

std::int64_t QueueRandom::retry_delay_ms(const QueuePolicy& policy, int attempts) {
  const double factor = std::uniform_real_distribution<double>(0.5, 1.5)(engine_);
  const double delay = std::min(3.6e6, static_cast<double>(policy.backoff_base.count()) *
                                           std::ldexp(1.0, std::min(attempts - 1, 20)) * factor);
  return static_cast<std::int64_t>(delay);
}

}  // namespace csgtile::worker::detail
