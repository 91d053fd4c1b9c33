#include "ops/metrics.h"

#include <charconv>
#include <cmath>

namespace csgtile::worker::ops {

const char* job_outcome_name(JobOutcome outcome) {
  switch (outcome) {
    case JobOutcome::Done:
      return "done";
    case JobOutcome::Retry:
      return "retry";
    case JobOutcome::Dead:
      return "dead";
    case JobOutcome::LeaseLost:
      return "lease_lost";
  }
  return "unknown";
}

const std::vector<double>& Metrics::duration_buckets() {
  // From a scene job (well under a second) to a dense LIDAR tile (tens of minutes).
  static const std::vector<double> buckets = {0.05, 0.1, 0.25, 0.5, 1,   2.5,  5,   10,
                                              30,   60,  120,  300, 600, 1800, 3600};
  return buckets;
}

Metrics::Metrics()
    : duration_counts_(duration_buckets().size() + 1, 0),
      last_progress_(std::chrono::steady_clock::now()),
      start_time_unix_(
          std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch())
              .count()) {}

void Metrics::job_claimed(int attempt) {
  const std::lock_guard lock(mutex_);
  if (attempt > 1) ++retries_;
  job_running_ = true;
  last_progress_ = std::chrono::steady_clock::now();
}

void Metrics::job_finished(JobOutcome outcome, double seconds) {
  const std::lock_guard lock(mutex_);
  ++outcomes_[static_cast<int>(outcome)];
  job_running_ = false;
  const auto& buckets = duration_buckets();
  std::size_t i = 0;
  while (i < buckets.size() && seconds > buckets[i]) ++i;  // le: value <= bound
  ++duration_counts_[i];
  duration_sum_ += seconds;
  ++duration_count_;
  last_progress_ = std::chrono::steady_clock::now();
}

void Metrics::add_stage_seconds(std::string_view stage, double seconds) {
  const std::lock_guard lock(mutex_);
  auto it = stage_seconds_.find(stage);
  if (it == stage_seconds_.end()) it = stage_seconds_.emplace(std::string(stage), 0.0).first;
  it->second += seconds;
}

void Metrics::mark_progress() {
  const std::lock_guard lock(mutex_);
  last_progress_ = std::chrono::steady_clock::now();
}

void Metrics::begin_long_step(std::string_view name) {
  const std::lock_guard lock(mutex_);
  long_step_ = name;
  last_progress_ = std::chrono::steady_clock::now();
}

void Metrics::end_long_step() {
  const std::lock_guard lock(mutex_);
  long_step_.clear();
  last_progress_ = std::chrono::steady_clock::now();
}

Metrics::Liveness Metrics::liveness() const {
  const std::lock_guard lock(mutex_);
  Liveness l;
  l.seconds_since_progress =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - last_progress_).count();
  l.long_step = long_step_;
  return l;
}

void append_sample_value(std::string& out, double value) {
  if (std::isnan(value)) {
    out += "NaN";
  } else if (std::isinf(value)) {
    out += value > 0 ? "+Inf" : "-Inf";
  } else {
    char buffer[64];
    const auto [end, ec] = std::to_chars(buffer, buffer + sizeof buffer, value);
    out.append(buffer, ec == std::errc() ? end : buffer);
  }
}

std::string escape_label_value(std::string_view value) {
  std::string out;
  out.reserve(value.size());
  for (const char c : value) {
    if (c == '\\')
      out += "\\\\";
    else if (c == '"')
      out += "\\\"";
    else if (c == '\n')
      out += "\\n";
    else
      out += c;
  }
  return out;
}

namespace {

void header(std::string& out, std::string_view name, std::string_view type, std::string_view help) {
  out.append("# HELP ").append(name).append(" ").append(help).append("\n");
  out.append("# TYPE ").append(name).append(" ").append(type).append("\n");
}

void sample(std::string& out, std::string_view name, std::string_view labels, double value) {
  out.append(name);
  if (!labels.empty()) out.append("{").append(labels).append("}");
  out += ' ';
  append_sample_value(out, value);
  out += '\n';
}

std::string label(std::string_view key, std::string_view value) {
  return std::string(key) + "=\"" + escape_label_value(value) + "\"";
}

}  // namespace

std::string Metrics::exposition() const {
  std::string out;
  const auto u = [](const std::atomic<std::uint64_t>& a) {
    return static_cast<double>(a.load(std::memory_order_relaxed));
  };
  header(out, "csgtile_fetched_bytes_total", "counter", "Bytes of inputs fetched by this worker.");
  sample(out, "csgtile_fetched_bytes_total", "", u(fetched_bytes_));
  header(out, "csgtile_published_bytes_total", "counter",
         "Bytes of outputs published (written) by this worker.");
  sample(out, "csgtile_published_bytes_total", "", u(published_bytes_));
  header(out, "csgtile_points_processed_total", "counter",
         "LIDAR points read by this worker's jobs.");
  sample(out, "csgtile_points_processed_total", "", u(points_processed_));
  header(out, "csgtile_primitives_built_total", "counter",
         "Primitives built into solids by this worker's jobs.");
  sample(out, "csgtile_primitives_built_total", "", u(primitives_built_));

  const std::lock_guard lock(mutex_);
  header(out, "csgtile_worker_jobs_total", "counter",
         "Job attempts run by this worker, by outcome (done, retry, dead, lease_lost).");
  for (const JobOutcome o :
       {JobOutcome::Done, JobOutcome::Retry, JobOutcome::Dead, JobOutcome::LeaseLost}) {
    sample(out, "csgtile_worker_jobs_total", label("outcome", job_outcome_name(o)),
           static_cast<double>(outcomes_[static_cast<int>(o)]));
  }
  header(out, "csgtile_worker_job_retries_total", "counter",
         "Jobs this worker claimed on their second or later attempt.");
  sample(out, "csgtile_worker_job_retries_total", "", static_cast<double>(retries_));
  header(out, "csgtile_worker_job_duration_seconds", "histogram",
         "Wall time of the job attempts run by this worker.");
  std::uint64_t cumulative = 0;
  const auto& buckets = duration_buckets();
  for (std::size_t i = 0; i <= buckets.size(); ++i) {
    cumulative += duration_counts_[i];
    std::string le;
    if (i < buckets.size()) {
      append_sample_value(le, buckets[i]);
    } else {
      le = "+Inf";
    }
    sample(out, "csgtile_worker_job_duration_seconds_bucket", label("le", le),
           static_cast<double>(cumulative));
  }
  sample(out, "csgtile_worker_job_duration_seconds_sum", "", duration_sum_);
  sample(out, "csgtile_worker_job_duration_seconds_count", "",
         static_cast<double>(duration_count_));
  header(out, "csgtile_worker_stage_seconds_total", "counter",
         "Wall time this worker's jobs spent in each stage (fetch, read, build, check, boolean, "
         "publish).");
  for (const auto& [stage, seconds] : stage_seconds_) {
    sample(out, "csgtile_worker_stage_seconds_total", label("stage", stage), seconds);
  }
  header(out, "csgtile_worker_job_running", "gauge", "1 while this worker runs a job.");
  sample(out, "csgtile_worker_job_running", "", job_running_ ? 1 : 0);
  header(out, "csgtile_worker_seconds_since_progress", "gauge",
         "Seconds since the work loop last made progress (the liveness check's measure).");
  sample(out, "csgtile_worker_seconds_since_progress", "",
         std::chrono::duration<double>(std::chrono::steady_clock::now() - last_progress_).count());
  header(out, "process_start_time_seconds", "gauge",
         "Start time of the process since the Unix epoch.");
  sample(out, "process_start_time_seconds", "", start_time_unix_);
  return out;
}

Metrics& metrics() {
  static Metrics registry;
  return registry;
}

}  // namespace csgtile::worker::ops
