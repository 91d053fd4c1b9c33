#pragma once
/// \file
/// Structured logging: one JSON object per line on stderr (level, time, component, run and job
/// ids while a job runs, message, fields), or a readable line when stderr is a terminal
/// (format "auto").

#include <cstdio>
#include <map>
#include <string>
#include <string_view>

#include "csgtile/config/config.h"

namespace csgtile::worker {

class Logger {
 public:
  /// `out` defaults to stderr. Format Auto picks Text on a terminal, else Json.
  explicit Logger(config::LogLevel level = config::LogLevel::Info,
                  config::LogFormat format = config::LogFormat::Auto, std::FILE* out = stderr);

  void set_job(std::string job_id) { job_id_ = std::move(job_id); }
  void log(config::LogLevel level, std::string_view component, std::string_view message,
           const std::map<std::string, std::string>& fields = {}) const;
  void info(std::string_view component, std::string_view message,
            const std::map<std::string, std::string>& fields = {}) const {
    log(config::LogLevel::Info, component, message, fields);
  }
  void error(std::string_view component, std::string_view message,
             const std::map<std::string, std::string>& fields = {}) const {
    log(config::LogLevel::Error, component, message, fields);
  }
  bool json() const { return json_; }

 private:
  config::LogLevel level_;
  bool json_;
  std::FILE* out_;
  std::string job_id_;
};

/// "trace", "debug", "info", "warn", "error".
const char* log_level_name(config::LogLevel level);

/// While alive, every line any Logger writes on this thread carries the running job's
/// context: JSON fields `run` (the run's name), `job` (the job's key) and `attempt`; text
/// `run=… job=… attempt=…`. The worker opens one around each job it runs. Scopes nest (the
/// innermost wins) and are per thread, so lines of other threads are unaffected.
class LogJobScope {
 public:
  LogJobScope(std::string run, std::string job, int attempt);
  ~LogJobScope();
  LogJobScope(const LogJobScope&) = delete;
  LogJobScope& operator=(const LogJobScope&) = delete;

 private:
  std::string previous_run_;
  std::string previous_job_;
  int previous_attempt_ = 0;
};

}  // namespace csgtile::worker
