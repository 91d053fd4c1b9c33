#include "queue/heartbeat.h"

#include "ops/metrics.h"

namespace csgtile::worker {

LeaseHeartbeat::LeaseHeartbeat(JobQueue& queue, Job job, std::chrono::milliseconds period)
    : queue_(queue),
      job_(std::move(job)),
      period_(std::max(period, std::chrono::milliseconds(10))) {
  thread_ = std::thread([this] { run(); });
}

LeaseHeartbeat::~LeaseHeartbeat() { stop(); }

void LeaseHeartbeat::stop() {
  {
    const std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
}

bool LeaseHeartbeat::lost() const {
  const std::lock_guard lock(mutex_);
  return lost_;
}

int LeaseHeartbeat::beats() const {
  const std::lock_guard lock(mutex_);
  return beats_;
}

void LeaseHeartbeat::run() {
  std::unique_lock lock(mutex_);
  while (!stopping_ && !lost_) {
    if (wake_.wait_for(lock, period_, [this] { return stopping_; })) break;
    lock.unlock();
    Failure failure;
    const bool held = queue_.renew(job_, failure);
    lock.lock();
    if (held) {
      ++beats_;
      ops::metrics().mark_progress();  // a long job keeps the worker live (/healthz)
    } else if (failure.ok()) {
      lost_ = true;  // the row said no: taken over, or no longer running
    }
  }
}

}  // namespace csgtile::worker
