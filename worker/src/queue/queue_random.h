#pragma once
// The queue's seeded random choices, shared by every backend so that, for one seed and one
// sequence of calls, each backend draws the same lease tokens and retry delays.

#include <cstdint>
#include <random>
#include <string>

#include "csgtile/worker/queue.h"

namespace csgtile::worker::detail {

class QueueRandom {
 public:
  explicit QueueRandom(std::uint64_t seed) : engine_(seed) {}

  /// "<worker>-<now_ms>-<draw>": one draw per successful claim.
  std::string lease_token(const std::string& worker_id, std::int64_t now_ms);

  /// Delay before the next attempt of a job that failed on attempt `attempts` (1-based):
  /// base · 2^(attempts-1) · U(0.5, 1.5), the exponent capped at 20 and the delay at an
  /// hour. One draw per call, made whether or not the job will retry.
  std::int64_t retry_delay_ms(const QueuePolicy& policy, int attempts);

 private:
  std::mt19937_64 engine_;
};

}  // namespace csgtile::worker::detail
