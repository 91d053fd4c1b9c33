#pragma once
/// \file
/// The one table of csgtile's error codes: message, whether a job may retry, and the
/// process exit code. Only main() exits; everything else returns these codes.

#include <string>
#include <string_view>

#include "csgtile/kernel/result.h"

namespace csgtile::worker {

enum class ErrorCode {
  Ok,
  Usage,            ///< bad command line
  ConfigInvalid,    ///< config file fails parsing or validation
  InputInvalid,     ///< an input (scene, tile) is malformed
  GeometryInvalid,  ///< geometry cannot be built or fails the validity checker
  Unsupported,      ///< a valid request this build does not handle yet
  Io,               ///< the operating system refused a read or write
  Internal,         ///< a bug: an invariant of csgtile itself failed
  ResultInvalid,    ///< the command ran, but its result fails validation
  JobsFailed,       ///< a run finished with some jobs dead
  Network,          ///< a transfer failed in a way that may pass (timeout, reset, HTTP 5xx)
  FetchRefused,     ///< a fetch the policy or the server refuses (scheme, address, size, 4xx)
  Cancelled,        ///< stopped before it finished: a stop request (shutdown) or a time limit
};

struct ErrorInfo {
  ErrorCode code;
  const char* name;     ///< stable snake_case name used in logs and job records
  const char* summary;  ///< one line for people
  bool retryable;       ///< a job failing with it may succeed on another attempt
  int exit_code;        ///< process exit status (never 124–127 or 137)
};

/// The row of `code` in the table.
const ErrorInfo& error_info(ErrorCode code);
/// All rows, in enum order (for the README and tests).
const ErrorInfo* error_table(std::size_t* count);

/// Maps a kernel error to the worker code that describes it.
ErrorCode from_kernel(kernel::ErrorCode code);

/// An error with its code and a message naming what is wrong.
struct Failure {
  ErrorCode code = ErrorCode::Ok;
  std::string message;
  bool ok() const { return code == ErrorCode::Ok; }
};

/// A kernel (or geo) error as the worker speaks it: from_kernel's code, and the message after
/// `context` and ": " when a context is given (what was being read or built).
Failure failure_of(const kernel::Error& error, const std::string& context = {});

}  // namespace csgtile::worker
