#pragma once
/// \file
/// The one table of csgtile's error codes: message, whether a job may retry, and the
/// process exit code. Only main() exits; everything else returns these codes.

#include <cassert>
#include <string>
#include <string_view>
#include <utility>
#include <variant>

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
  ResourceLimit,    ///< a job went over a configured resource bound (queue.job_memory_mib)
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

/// Either a value or a Failure: what the worker's own fallible calls return when they have a
/// value to give (a call with none returns a Failure, ok() when it worked). The worker's
/// counterpart of kernel::Result, so that one error type crosses the worker's modules.
template <class T>
class [[nodiscard]] Result {
 public:
  Result(T value) : data_(std::move(value)) {}  // NOLINT(google-explicit-constructor)
  /// `failure` must not be ok().
  Result(Failure failure) : data_(std::move(failure)) {  // NOLINT(google-explicit-constructor)
    assert(!std::get<1>(data_).ok());
  }
  Result(ErrorCode code, std::string message) : Result(Failure{code, std::move(message)}) {}

  bool ok() const { return data_.index() == 0; }
  const T& value() const& { return std::get<0>(data_); }
  T& value() & { return std::get<0>(data_); }
  T&& value() && { return std::get<0>(std::move(data_)); }
  const T& operator*() const& { return value(); }
  const T* operator->() const { return &value(); }
  const Failure& error() const { return std::get<1>(data_); }

 private:
  std::variant<T, Failure> data_;
};

/// A kernel (or geo) error as the worker speaks it: from_kernel's code, and the message after
/// `context` and ": " when a context is given (what was being read or built).
Failure failure_of(const kernel::Error& error, const std::string& context = {});

}  // namespace csgtile::worker
