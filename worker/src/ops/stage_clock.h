#pragma once
// Per-job stage timing: `enter("build")` closes the stage running and opens another; the
// seconds of each stage add up (a stage entered twice, e.g. build and check alternating per
// primitive, accumulates) into a StageTimings (run.h) and into the metrics registry's
// csgtile_worker_stage_seconds_total. Not thread-safe: one clock per job, on its thread.

#include <chrono>
#include <string>
#include <string_view>

#include "csgtile/worker/job_support.h"

namespace csgtile::worker::ops {

class StageClock {
 public:
  /// `out` may be null: then only the metrics registry is fed.
  explicit StageClock(StageTimings* out) : out_(out) {}
  ~StageClock() { stop(); }
  StageClock(const StageClock&) = delete;
  StageClock& operator=(const StageClock&) = delete;

  /// Closes the running stage (if any) and starts `stage`.
  void enter(std::string_view stage);
  /// Closes the running stage (idempotent).
  void stop();

 private:
  StageTimings* out_;
  std::string stage_;
  std::chrono::steady_clock::time_point since_;
};

}  // namespace csgtile::worker::ops
