#include "csgtile/kernel/orientation.h"
#include "csgtile/kernel/result.h"

namespace csgtile::kernel {

const char* error_code_name(ErrorCode code) {
  switch (code) {
    case ErrorCode::InvalidArgument:
      return "invalid_argument";
    case ErrorCode::InvalidLocation:
      return "invalid_location";
    case ErrorCode::DegenerateGeometry:
      return "degenerate_geometry";
    case ErrorCode::InvalidShape:
      return "invalid_shape";
    case ErrorCode::CorruptData:
      return "corrupt_data";
    case ErrorCode::UnsupportedVersion:
      return "unsupported_version";
    case ErrorCode::IoError:
      return "io_error";
    case ErrorCode::Unsupported:
      return "unsupported";
    case ErrorCode::Cancelled:
      return "cancelled";
  }
  return "unknown";
}

const char* orientation_name(Orientation o) {
  switch (o) {
    case Orientation::Forward:
      return "forward";
    case Orientation::Reversed:
      return "reversed";
    case Orientation::Internal:
      return "internal";
    case Orientation::External:
      return "external";
  }
  return "unknown";
}

}  // namespace csgtile::kernel
