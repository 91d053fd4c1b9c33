#include "csgtile/worker/log.h"

#include <unistd.h>

#include <chrono>
#include <ctime>
#include <nlohmann/json.hpp>

namespace csgtile::worker {

const char* log_level_name(config::LogLevel level) { return config::to_string(level).data(); }

Logger::Logger(config::LogLevel level, config::LogFormat format, std::FILE* out)
    : level_(level), out_(out) {
  json_ = format == config::LogFormat::Json ||
          (format == config::LogFormat::Auto && !isatty(fileno(out)));
}

namespace {

/// The job this thread is running (LogJobScope); empty job: none.
struct JobContext {
  std::string run;
  std::string job;
  int attempt = 0;
};
thread_local JobContext t_job_context;

std::string utc_now() {
  const auto now = std::chrono::system_clock::now();
  const std::time_t t = std::chrono::system_clock::to_time_t(now);
  const auto ms =
      std::chrono::duration_cast<std::chrono::milliseconds>(now.time_since_epoch()).count() % 1000;
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[64];
  std::snprintf(buf, sizeof buf, "%04d-%02d-%02dT%02d:%02d:%02d.%03dZ", tm.tm_year + 1900,
                tm.tm_mon + 1, tm.tm_mday, tm.tm_hour, tm.tm_min, tm.tm_sec, static_cast<int>(ms));
  return buf;
}
}  // namespace

LogJobScope::LogJobScope(std::string run, std::string job, int attempt)
    : previous_run_(std::move(t_job_context.run)),
      previous_job_(std::move(t_job_context.job)),
      previous_attempt_(t_job_context.attempt) {
  t_job_context = {std::move(run), std::move(job), attempt};
}

LogJobScope::~LogJobScope() {
  t_job_context = {std::move(previous_run_), std::move(previous_job_), previous_attempt_};
}

void Logger::log(config::LogLevel level, std::string_view component, std::string_view message,
                 const std::map<std::string, std::string>& fields) const {
  if (static_cast<int>(level) < static_cast<int>(level_)) return;
  std::string line;
  if (json_) {
    nlohmann::ordered_json j;
    j["time"] = utc_now();
    j["level"] = log_level_name(level);
    j["component"] = component;
    if (!t_job_context.job.empty()) {
      j["run"] = t_job_context.run;
      j["job"] = t_job_context.job;
      j["attempt"] = t_job_context.attempt;
    }
    if (!job_id_.empty()) j["job"] = job_id_;
    j["message"] = message;
    for (const auto& [k, v] : fields) j[k] = v;
    // Invalid UTF-8 in a message (a file name, say) is replaced, never breaks the line.
    line = j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
  } else {
    // append() rather than operator+ chains: GCC 12 at -O3 warns falsely (-Wrestrict) on those.
    line.append(utc_now()).append(" ").append(log_level_name(level)).append(" [");
    line.append(component).append("]");
    if (!t_job_context.job.empty() && job_id_.empty()) {
      line.append(" run=").append(t_job_context.run).append(" job=").append(t_job_context.job);
      line.append(" attempt=").append(std::to_string(t_job_context.attempt));
    }
    if (!job_id_.empty()) line.append(" job=").append(job_id_);
    line.append(" ").append(message);
    for (const auto& [k, v] : fields) line.append(" ").append(k).append("=").append(v);
  }
  line += '\n';
  std::fwrite(line.data(), 1, line.size(), out_);
  std::fflush(out_);
}

}  // namespace csgtile::worker
