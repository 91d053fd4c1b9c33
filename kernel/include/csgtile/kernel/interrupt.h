#pragma once
/// \file
/// Cooperative cancellation of long kernel operations (Booleans, n-ary fuses, the assembly,
/// the fit): they look at an Interrupt between their steps — a face pair, a face split, a
/// piece classified, a pairwise fuse — and return ErrorCode::Cancelled when it has fired,
/// leaving their arguments untouched. It fires when its stop token is asked to stop (by
/// another thread: a worker shutting down) or when its deadline passes (a time limit per
/// building). A default Interrupt never fires and costs one branch per look.

#include <chrono>
#include <optional>
#include <stop_token>
#include <string>

#include "csgtile/kernel/result.h"

namespace csgtile::kernel {

struct Interrupt {
  using Clock = std::chrono::steady_clock;

  std::stop_token stop{};                       ///< fires once its source asks to stop
  std::optional<Clock::time_point> deadline{};  ///< fires once the clock passes it
  double limit_seconds = 0;  ///< the time limit the deadline came from (for messages)

  /// This interrupt with a deadline `seconds` from now (the earlier one where it had one);
  /// `seconds` ≤ 0 adds none.
  Interrupt within(double seconds) const;

  /// Whether it has fired: its token was asked to stop, or its deadline has passed.
  bool fired() const {
    if (stop.stop_requested()) return true;
    return deadline && Clock::now() >= *deadline;
  }

  /// The error an operation stopped by it returns: Cancelled, naming why (a stop request or
  /// the time limit) and `where` it stopped.
  Error error(const std::string& where) const;

  /// Status::ok() while it has not fired, else error(where).
  Status check(const std::string& where) const { return fired() ? Status(error(where)) : Status(); }

  /// Same token (stop state), deadline and limit (options holding one compare with it).
  bool operator==(const Interrupt&) const = default;
};

}  // namespace csgtile::kernel
