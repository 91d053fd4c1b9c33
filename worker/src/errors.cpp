#include "csgtile/worker/errors.h"

#include <array>

namespace csgtile::worker {

namespace {
// Exit codes follow sysexits(3) where one fits; 1 and 3 report a command that ran but whose
// result is not clean (an invalid solid, dead jobs) — see README "Exit codes".
constexpr std::array<ErrorInfo, 14> kTable{{
    {ErrorCode::Ok, "ok", "success", false, 0},
    {ErrorCode::Usage, "usage", "bad command line", false, 64},
    {ErrorCode::ConfigInvalid, "config_invalid", "the configuration is invalid", false, 78},
    {ErrorCode::InputInvalid, "input_invalid", "an input file is malformed", false, 65},
    {ErrorCode::GeometryInvalid, "geometry_invalid", "geometry cannot be built or is invalid",
     false, 66},
    {ErrorCode::Unsupported, "unsupported", "not supported by this build", false, 69},
    {ErrorCode::Io, "io", "a read or write failed", true, 74},
    {ErrorCode::Internal, "internal", "internal error (a bug in csgtile)", false, 70},
    {ErrorCode::ResultInvalid, "result_invalid", "the result fails validation", false, 1},
    {ErrorCode::JobsFailed, "jobs_failed", "the run finished with dead jobs", false, 3},
    {ErrorCode::Network, "network", "a transfer failed (timeout, reset, server error)", true, 75},
    {ErrorCode::FetchRefused, "fetch_refused", "a fetch was refused (policy, size, HTTP 4xx)",
     false, 77},
    {ErrorCode::Cancelled, "cancelled", "stopped before it finished (a stop request)", true, 80},
    {ErrorCode::ResourceLimit, "resource_limit", "a job went over its memory bound", false, 81},
}};
}  // namespace

const ErrorInfo& error_info(ErrorCode code) { return kTable[static_cast<std::size_t>(code)]; }

const ErrorInfo* error_table(std::size_t* count) {
  *count = kTable.size();
  return kTable.data();
}

ErrorCode from_kernel(kernel::ErrorCode code) {
  switch (code) {
    case kernel::ErrorCode::InvalidArgument:
    case kernel::ErrorCode::CorruptData:
    case kernel::ErrorCode::UnsupportedVersion:
      return ErrorCode::InputInvalid;
    case kernel::ErrorCode::InvalidLocation:
    case kernel::ErrorCode::DegenerateGeometry:
    case kernel::ErrorCode::InvalidShape:
      return ErrorCode::GeometryInvalid;
    case kernel::ErrorCode::IoError:
      return ErrorCode::Io;
    case kernel::ErrorCode::Unsupported:
      return ErrorCode::Unsupported;
    case kernel::ErrorCode::Cancelled:
      return ErrorCode::Cancelled;
  }
  return ErrorCode::Internal;
}

Failure failure_of(const kernel::Error& error, const std::string& context) {
  return {from_kernel(error.code),
          context.empty() ? error.message : context + ": " + error.message};
}

}  // namespace csgtile::worker
