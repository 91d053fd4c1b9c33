// Real roots of polynomials (polynomial.h): noise-aware isolation between the roots of the
// derivative, and the cancellation-free quadratic.

#include "csgtile/kernel/polynomial.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <utility>

namespace csgtile::kernel {

namespace {

constexpr double kEps = std::numeric_limits<double>::epsilon();
constexpr int kMaxDegree = 8;

struct Evaluation {
  double value;
  double noise;  // bound on the rounding error of `value`
};

Evaluation evaluate(const double* c, const double* m, int n, double x) {
  double v = c[n];
  double a = std::abs(c[n]) + (m != nullptr ? m[n] : 0.0);
  const double ax = std::abs(x);
  for (int i = n - 1; i >= 0; --i) {
    v = v * x + c[i];
    a = a * ax + std::abs(c[i]) + (m != nullptr ? m[i] : 0.0);
  }
  // Horner's error is below 2n·eps·Σ|c_i||x|^i; the factor leaves room for the coefficients'
  // own rounding (recorded in m when the caller knows it).
  return {v, 16.0 * (n + 2) * kEps * a};
}

double derivative_at(const double* c, int n, double x) {
  double v = n * c[n];
  for (int i = n - 1; i >= 1; --i) v = v * x + i * c[i];
  return v;
}

// The root of a polynomial that is monotone on [a, b] with f(a), f(b) of opposite signs:
// Newton steps kept inside the shrinking bracket, bisection when a step leaves it or every
// fourth iteration (so that slow Newton convergence cannot stall the bracket).
double refine_monotone_root(const double* c, int n, double a, double b, double fa) {
  double x = 0.5 * (a + b);
  for (int iteration = 0; iteration < 200; ++iteration) {
    const double f = evaluate(c, nullptr, n, x).value;
    if (f == 0.0) return x;
    if ((f < 0.0) == (fa < 0.0)) {
      a = x;
      fa = f;
    } else {
      b = x;
    }
    if (b - a <= 4.0 * kEps * std::max(std::abs(a), std::abs(b))) return 0.5 * (a + b);
    const double df = derivative_at(c, n, x);
    double next = df != 0.0 ? x - f / df : 0.5 * (a + b);
    if (iteration % 4 == 3 || !(next > a && next < b)) next = 0.5 * (a + b);
    if (next == x) return x;
    x = next;
  }
  return x;
}

void polynomial_roots_impl(const double* c, const double* m, int n, double lo, double hi,
                           std::vector<PolynomialRoot>& out) {
  while (n > 0 && c[n] == 0.0) --n;
  if (n <= 0 || !(lo <= hi)) return;
  if (n == 1) {
    const double x = -c[0] / c[1];
    if (x >= lo && x <= hi) out.push_back({x, false});
    return;
  }
  std::array<double, kMaxDegree> dc{};
  std::array<double, kMaxDegree> dm{};
  for (int i = 0; i < n; ++i) {
    dc[static_cast<std::size_t>(i)] = (i + 1) * c[i + 1];
    dm[static_cast<std::size_t>(i)] = (i + 1) * (m != nullptr ? m[i + 1] : 0.0);
  }
  std::vector<PolynomialRoot> critical;
  polynomial_roots_impl(dc.data(), dm.data(), n - 1, lo, hi, critical);

  // Breakpoints lo < critical points < hi; between two consecutive ones f is monotone.
  std::array<double, kMaxDegree + 2> x{};
  std::array<bool, kMaxDegree + 2> is_critical{};
  std::size_t count = 0;
  x[count] = lo;
  is_critical[count++] = false;
  for (const PolynomialRoot& r : critical) {
    if (r.x > x[count - 1] && r.x < hi) {
      x[count] = r.x;
      is_critical[count++] = true;
    }
  }
  x[count] = hi;
  is_critical[count++] = false;

  std::array<Evaluation, kMaxDegree + 2> f{};
  for (std::size_t k = 0; k < count; ++k) f[k] = evaluate(c, m, n, x[k]);
  auto sign = [&](std::size_t k) {
    if (std::abs(f[k].value) <= f[k].noise) return 0;
    return f[k].value > 0.0 ? 1 : -1;
  };
  for (std::size_t k = 0; k < count; ++k) {
    const int s = sign(k);
    if (s == 0) {
      // Within rounding of zero: a multiple root at a critical point; an (unflagged) root
      // at an end of the interval otherwise.
      out.push_back({x[k], is_critical[k]});
      continue;
    }
    if (k + 1 < count) {
      const int next = sign(k + 1);
      if (next != 0 && next != s) {
        out.push_back({refine_monotone_root(c, n, x[k], x[k + 1], f[k].value), false});
      }
    }
  }
}

}  // namespace

void polynomial_roots(const double* c, int degree, double lo, double hi,
                      std::vector<PolynomialRoot>& out, const double* magnitude) {
  const std::size_t first = out.size();
  polynomial_roots_impl(c, magnitude, std::min(degree, kMaxDegree), lo, hi, out);
  std::sort(out.begin() + static_cast<std::ptrdiff_t>(first), out.end(),
            [](const PolynomialRoot& a, const PolynomialRoot& b) { return a.x < b.x; });
}

int solve_quadratic(double a, double hb, double c, double c_magnitude, std::array<double, 2>& r,
                    bool& multiple) {
  multiple = false;
  if (a == 0.0) {
    if (hb == 0.0) return 0;
    r[0] = -c / (2.0 * hb);
    return 1;
  }
  const double disc = hb * hb - a * c;
  const double noise = 16.0 * kEps * (hb * hb + std::abs(a) * (std::abs(c) + c_magnitude));
  if (disc < -noise) return 0;
  if (disc <= noise) {
    r[0] = -hb / a;
    multiple = true;
    return 1;
  }
  const double q = -(hb + std::copysign(std::sqrt(disc), hb));
  r[0] = q / a;
  r[1] = c / q;
  if (r[0] > r[1]) std::swap(r[0], r[1]);
  return 2;
}

}  // namespace csgtile::kernel
