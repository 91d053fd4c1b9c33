#pragma once
/// \file
/// A helper process for tests (a loopback HTTP or S3 server): started with /bin/sh -c,
/// its first stdout line read (servers print their port there), killed with its process
/// group when the object dies.

#include <sys/types.h>
#include <string>

namespace csgtile::test {

class BackgroundProcess {
 public:
  /// Starts `command`; waits up to `timeout_seconds` for its first stdout line.
  explicit BackgroundProcess(const std::string& command, double timeout_seconds = 20.0);
  ~BackgroundProcess();
  BackgroundProcess(const BackgroundProcess&) = delete;
  BackgroundProcess& operator=(const BackgroundProcess&) = delete;

  bool running() const { return pid_ > 0 && !first_line_.empty(); }
  /// The first line the process printed (without the newline); empty when it printed
  /// none in time or exited.
  const std::string& first_line() const { return first_line_; }
  /// Why it is not running (exit status, timeout), for skip/failure messages.
  const std::string& problem() const { return problem_; }

 private:
  pid_t pid_ = -1;
  int out_ = -1;
  std::string first_line_;
  std::string problem_;
};

}  // namespace csgtile::test
