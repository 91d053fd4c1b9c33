#pragma once
// Seeded random numbers that are the same with every standard library: std::mt19937_64's
// output sequence is fixed by the standard, but uniform_real_distribution and
// normal_distribution are not, so the transforms are our own.

#include <cmath>
#include <cstdint>
#include <random>

namespace csgtile::geo::detail {

class Random {
 public:
  explicit Random(std::uint64_t seed) : engine_(seed) {}

  /// Uniform in [0, 1): the top 53 bits of one draw.
  double uniform() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }
  /// Uniform in [lo, hi).
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  /// Uniform integer in [0, n) for n >= 1 (the tiny modulo bias does not matter here).
  std::uint64_t below(std::uint64_t n) { return engine_() % n; }
  /// Standard normal by Marsaglia's polar method: only sqrt (exact in IEEE) and log.
  double normal() {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    for (;;) {
      const double u = 2.0 * uniform() - 1.0;
      const double v = 2.0 * uniform() - 1.0;
      const double s = u * u + v * v;
      if (s > 0.0 && s < 1.0) {
        const double f = std::sqrt(-2.0 * std::log(s) / s);
        spare_ = v * f;
        has_spare_ = true;
        return u * f;
      }
    }
  }

 private:
  std::mt19937_64 engine_;
  double spare_ = 0.0;
  bool has_spare_ = false;
};

}  // namespace csgtile::geo::detail
