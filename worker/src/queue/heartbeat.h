#pragma once
// Lease heartbeat: while a job runs, its lease is renewed on a thread of its own every
// `period` (a third of the lease is a good choice), so a long job keeps its lease and a dead
// worker's job is reclaimed one lease after its last beat.

#include <chrono>
#include <condition_variable>
#include <mutex>
#include <thread>

#include "csgtile/worker/queue.h"

namespace csgtile::worker {

class LeaseHeartbeat {
 public:
  /// Starts beating for `job` on `queue` (which must outlive this object).
  LeaseHeartbeat(JobQueue& queue, Job job, std::chrono::milliseconds period);
  ~LeaseHeartbeat();  ///< stops
  LeaseHeartbeat(const LeaseHeartbeat&) = delete;
  LeaseHeartbeat& operator=(const LeaseHeartbeat&) = delete;

  /// Stops beating (idempotent); returns once the thread has ended.
  void stop();
  /// Whether a renewal found the lease gone: the job must then be neither completed nor
  /// published. A renewal that failed for I/O is retried at the next beat.
  bool lost() const;
  /// Renewals that succeeded.
  int beats() const;

 private:
  void run();

  JobQueue& queue_;
  const Job job_;
  const std::chrono::milliseconds period_;
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  bool stopping_ = false;
  bool lost_ = false;
  int beats_ = 0;
  std::thread thread_;
};

}  // namespace csgtile::worker
