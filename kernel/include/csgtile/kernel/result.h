#pragma once
/// \file
/// Errors as data: the closed set of kernel error codes and a small Result<T>.
/// The kernel never throws across its API; every fallible call returns Result.

#include <cassert>
#include <string>
#include <utility>
#include <variant>

namespace csgtile::kernel {

/// Every way a kernel call can fail. Stable: codes are written into logs and job records.
enum class ErrorCode {
  InvalidArgument,     ///< a parameter is out of its documented range (negative radius, ...)
  InvalidLocation,     ///< a transform is singular, not a similarity, or mirrors
  DegenerateGeometry,  ///< geometry collapses (zero-area profile, coincident points, ...)
  InvalidShape,        ///< a shape fails the validity checker or has the wrong kind
  CorruptData,         ///< a serialised model is truncated, has a bad checksum or bad records
  UnsupportedVersion,  ///< a serialised model has a format version this build cannot read
  IoError,             ///< the operating system refused a read or write
  Unsupported,         ///< a valid request this kernel version does not handle
  Cancelled,           ///< stopped before it finished: a stop request or a time limit (interrupt.h)
};

/// Short stable name of a code, e.g. "invalid_location".
const char* error_code_name(ErrorCode code);

/// An error: its code and a message naming what is wrong.
struct Error {
  ErrorCode code;
  std::string message;
};

/// Either a value or an Error. Cheap to move; check ok() before value().
template <class T>
class [[nodiscard]] Result {
 public:
  Result(T value) : data_(std::move(value)) {}      // NOLINT: implicit by design
  Result(Error error) : data_(std::move(error)) {}  // NOLINT: implicit by design
  Result(ErrorCode code, std::string message) : data_(Error{code, std::move(message)}) {}

  bool ok() const { return data_.index() == 0; }
  explicit operator bool() const { return ok(); }

  const T& value() const& {
    assert(ok());
    return std::get<0>(data_);
  }
  T& value() & {
    assert(ok());
    return std::get<0>(data_);
  }
  T&& value() && {
    assert(ok());
    return std::get<0>(std::move(data_));
  }
  const T& operator*() const& { return value(); }
  const T* operator->() const { return &value(); }

  const Error& error() const {
    assert(!ok());
    return std::get<1>(data_);
  }

 private:
  std::variant<T, Error> data_;
};

/// Result of a call that returns nothing on success.
class [[nodiscard]] Status {
 public:
  Status() = default;
  Status(Error error) : error_(std::move(error)), ok_(false) {}  // NOLINT: implicit by design
  Status(ErrorCode code, std::string message) : error_{code, std::move(message)}, ok_(false) {}
  bool ok() const { return ok_; }
  explicit operator bool() const { return ok_; }
  const Error& error() const {
    assert(!ok_);
    return error_;
  }

 private:
  Error error_{ErrorCode::InvalidArgument, {}};
  bool ok_ = true;
};

}  // namespace csgtile::kernel
