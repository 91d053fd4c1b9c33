// Cooperative cancellation (interrupt.h): deadlines and the Cancelled error's wording.

#include "csgtile/kernel/interrupt.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace csgtile::kernel {

Interrupt Interrupt::within(double seconds) const {
  Interrupt out = *this;
  if (!(seconds > 0) || !std::isfinite(seconds)) return out;
  const auto at = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                     std::chrono::duration<double>(seconds));
  if (!out.deadline || at < *out.deadline) {
    out.deadline = at;
    out.limit_seconds = seconds;
  }
  return out;
}

Error Interrupt::error(const std::string& where) const {
  if (stop.stop_requested()) return {ErrorCode::Cancelled, "stopped on request " + where};
  std::ostringstream limit;
  limit << limit_seconds;
  return {ErrorCode::Cancelled, "time limit of " + limit.str() + " s reached " + where};
}

}  // namespace csgtile::kernel
