#pragma once
// The worker's process-wide metrics registry: counters and a histogram that the job loop,
// fetch and publish code update, rendered in the Prometheus text exposition format 0.0.4 by
// the ops endpoint (ops_server.h). Every member function is thread-safe; the hot ones (byte
// counters, called from transfer callbacks) are single relaxed atomic adds.
//
// Metric names are a contract with deploy manifests and dashboards (README "Metrics and
// health"): rename only together with them.

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <mutex>
#include <string>
#include <string_view>
#include <vector>

namespace csgtile::worker::ops {

/// How one job attempt run by this worker ended.
enum class JobOutcome {
  Done,       ///< completed
  Retry,      ///< failed, scheduled for another attempt
  Dead,       ///< failed for good (permanent error or attempts exhausted)
  LeaseLost,  ///< another worker took the job over; the outcome was discarded (fencing)
};
const char* job_outcome_name(JobOutcome outcome);

class Metrics {
 public:
  Metrics();

  void add_bytes_fetched(std::uint64_t bytes) {
    fetched_bytes_.fetch_add(bytes, std::memory_order_relaxed);
  }
  void add_bytes_published(std::uint64_t bytes) {
    published_bytes_.fetch_add(bytes, std::memory_order_relaxed);
  }
  void add_points_processed(std::uint64_t points) {
    points_processed_.fetch_add(points, std::memory_order_relaxed);
  }
  void add_primitives_built(std::uint64_t primitives) {
    primitives_built_.fetch_add(primitives, std::memory_order_relaxed);
  }

  /// A job was claimed on its `attempt`-th attempt (a second or later attempt counts as a
  /// retry); marks a job running and the loop as progressing.
  void job_claimed(int attempt);
  /// The running job ended with `outcome` after `seconds`; marks progress.
  void job_finished(JobOutcome outcome, double seconds);
  /// Adds `seconds` spent in a job stage ("read", "build", …).
  void add_stage_seconds(std::string_view stage, double seconds);

  /// Liveness: the work loop (or a lease renewal of its running job) did something now.
  void mark_progress();
  /// Publishing a run has no natural beats: while a long step is under way the worker is
  /// reported live (a step that hangs is then not detected; see README "Metrics and health").
  void begin_long_step(std::string_view name);
  void end_long_step();

  struct Liveness {
    double seconds_since_progress = 0;
    std::string long_step;  ///< non-empty while a long step runs
  };
  Liveness liveness() const;

  /// The registry's metrics as exposition text (HELP, TYPE, samples; ends with '\n').
  std::string exposition() const;

  /// Upper bounds (seconds) of the job duration histogram buckets, ascending; +Inf implied.
  static const std::vector<double>& duration_buckets();

 private:
  std::atomic<std::uint64_t> fetched_bytes_{0};
  std::atomic<std::uint64_t> published_bytes_{0};
  std::atomic<std::uint64_t> points_processed_{0};
  std::atomic<std::uint64_t> primitives_built_{0};

  mutable std::mutex mutex_;  // guards everything below
  std::uint64_t outcomes_[4] = {0, 0, 0, 0};
  std::uint64_t retries_ = 0;
  bool job_running_ = false;
  std::vector<std::uint64_t> duration_counts_;  // per bucket, not cumulative; last is +Inf
  double duration_sum_ = 0;
  std::uint64_t duration_count_ = 0;
  std::map<std::string, double, std::less<>> stage_seconds_;  // sorted: stable output order
  std::chrono::steady_clock::time_point last_progress_;
  std::string long_step_;
  double start_time_unix_ = 0;
};

/// The process's registry (a function-local static: constructed on first use).
Metrics& metrics();

/// Marks a long step (begin_long_step … end_long_step) for the lifetime of the scope.
class LongStepScope {
 public:
  LongStepScope(Metrics& registry, std::string_view name) : registry_(registry) {
    registry_.begin_long_step(name);
  }
  ~LongStepScope() { registry_.end_long_step(); }
  LongStepScope(const LongStepScope&) = delete;
  LongStepScope& operator=(const LongStepScope&) = delete;

 private:
  Metrics& registry_;
};

/// Appends `value` as a sample value: integers without a fraction, others in shortest
/// round-trip form; +Inf, -Inf and NaN as the format spells them.
void append_sample_value(std::string& out, double value);

/// Escapes a label value (backslash, double quote, newline) for the exposition format.
std::string escape_label_value(std::string_view value);

}  // namespace csgtile::worker::ops
