#pragma once
/// \file
/// Helpers shared by the geometry sources: angle ranges, exact extremes of trigonometric
/// functions over parameter intervals, adaptive Gauss–Legendre quadrature and the planar
/// point-to-ellipse solver. Not API.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <limits>
#include <numbers>
#include <utility>

#include "csgtile/kernel/bounding_box.h"
#include "csgtile/kernel/curve.h"
#include "csgtile/kernel/frame.h"
#include "csgtile/kernel/surface.h"

namespace csgtile::kernel::detail {

/// The factor on an edge's parameter range once its curve is moved by `loc` (transformed()):
/// a line keeps a unit direction, so its arc length scales; angles do not.
inline double moved_parameter_scale(const Curve& curve, const Location& loc) {
  return curve.kind() == CurveKind::Line ? loc.scale() : 1.0;
}

inline constexpr double kPi = std::numbers::pi;
inline constexpr double kTwoPi = 2.0 * std::numbers::pi;

/// `a` reduced into [0, 2π). fmod keeps large angles accurate; the last test catches
/// -tiny + 2π rounding up to 2π.
inline double wrap_two_pi(double a) {
  double r = std::fmod(a, kTwoPi);
  if (r < 0.0) r += kTwoPi;
  if (r >= kTwoPi) r = 0.0;
  return r;
}

/// The smallest t ≥ t0 with t ≡ a (mod 2π).
inline double first_angle_at_or_after(double a, double t0) { return t0 + wrap_two_pi(a - t0); }

/// Whether some t ≡ a (mod 2π) lies in [t0, t1].
inline bool angle_in_range(double a, double t0, double t1) {
  return first_angle_at_or_after(a, t0) <= t1;
}

/// A closed interval of values.
struct ValueRange {
  double min, max;
};

/// Exact range of a·cos t + b·sin t over t ∈ [t0, t1] (any t0 ≤ t1, also longer than 2π):
/// the extremes are at the endpoints or at the critical angles atan2(b, a) (+π).
inline ValueRange trig_range(double a, double b, double t0, double t1) {
  if (t1 < t0) std::swap(t0, t1);
  const double e0 = a * std::cos(t0) + b * std::sin(t0);
  const double e1 = a * std::cos(t1) + b * std::sin(t1);
  ValueRange r{std::min(e0, e1), std::max(e0, e1)};
  if (a == 0.0 && b == 0.0) return r;
  const double amplitude = std::hypot(a, b);
  const double peak = std::atan2(b, a);
  if (angle_in_range(peak, t0, t1)) r.max = amplitude;
  if (angle_in_range(peak + kPi, t0, t1)) r.min = -amplitude;
  return r;
}

/// Range of α·t + β over t ∈ [t0, t1]; a zero slope never multiplies an infinite bound.
inline ValueRange linear_range(double slope, double offset, double t0, double t1) {
  if (slope == 0.0) return {offset, offset};
  const double e0 = slope * t0 + offset;
  const double e1 = slope * t1 + offset;
  return {std::min(e0, e1), std::max(e0, e1)};
}

/// Candidate angles for the extremes of cos u·x + sin u·y over u ∈ [u0, u1]: the endpoints
/// and the first occurrence of each critical angle atan2(y, x) + kπ inside. Later
/// occurrences repeat the same values, so at most four candidates are needed.
struct AngleCandidates {
  std::array<double, 4> values{};
  int count = 0;
  void push(double u) { values[static_cast<std::size_t>(count++)] = u; }
};

inline AngleCandidates critical_angle_candidates(double x, double y, double u0, double u1) {
  if (u1 < u0) std::swap(u0, u1);
  AngleCandidates c;
  c.push(u0);
  c.push(u1);
  if (x == 0.0 && y == 0.0) return c;
  const double psi = std::atan2(y, x);
  for (double a : {psi, psi + kPi}) {
    const double u = first_angle_at_or_after(a, u0);
    if (u < u1) c.push(u);
  }
  return c;
}

/// Exact bounds of the rotational patch
///   S(u, v) = O + ρ(v)·(cos u·X + sin u·Y) + h(v)·Z,   (u, v) ∈ box,
/// given `v_range(α, β, v0, v1)`, the exact range of α·ρ(v) + β·h(v) over [v0, v1].
/// Per coordinate i the u-critical points of ρ(v)·(cos u·X_i + sin u·Y_i) are at
/// atan2(Y_i, X_i) + kπ whatever the sign of ρ(v), so the extremes over the patch are
/// attained at those u (or the u-endpoints) and the 1-D v-extremes there.
template <class VRange>
BoundingBox rotational_patch_bounds(const Frame& f, const ParamBox& box, VRange&& v_range) {
  BoundingBox out;
  for (int i = 0; i < 3; ++i) {
    const AngleCandidates us = critical_angle_candidates(f.x[i], f.y[i], box.u0, box.u1);
    double lo = std::numeric_limits<double>::infinity();
    double hi = -lo;
    for (int k = 0; k < us.count; ++k) {
      const double u = us.values[static_cast<std::size_t>(k)];
      const double alpha = std::cos(u) * f.x[i] + std::sin(u) * f.y[i];
      const ValueRange r = v_range(alpha, f.z[i], box.v0, box.v1);
      lo = std::min(lo, r.min);
      hi = std::max(hi, r.max);
    }
    out.min[i] = f.origin[i] + lo;
    out.max[i] = f.origin[i] + hi;
  }
  return out;
}

/// 16-point Gauss–Legendre rule on [-1, 1], computed once by Newton iteration on P_16.
struct GaussLegendreRule {
  static constexpr int kOrder = 16;
  std::array<double, kOrder> nodes{};
  std::array<double, kOrder> weights{};
};
const GaussLegendreRule& gauss_legendre_rule();

template <class F>
double gauss_legendre(const F& f, double a, double b) {
  const GaussLegendreRule& rule = gauss_legendre_rule();
  const double half = 0.5 * (b - a);
  const double mid = 0.5 * (a + b);
  double sum = 0.0;
  for (int k = 0; k < GaussLegendreRule::kOrder; ++k) {
    const auto i = static_cast<std::size_t>(k);
    sum += rule.weights[i] * f(mid + half * rule.nodes[i]);
  }
  return half * sum;
}

template <class F>
double adaptive_gauss_legendre(const F& f, double a, double b, double whole, double tolerance,
                               int depth) {
  const double mid = 0.5 * (a + b);
  const double left = gauss_legendre(f, a, mid);
  const double right = gauss_legendre(f, mid, b);
  // |left + right - whole| estimates the error of `whole`; the halves are far more accurate
  // for the smooth integrands used here, so accepting them keeps a safety margin.
  if (depth >= 40 || std::abs(left + right - whole) <= tolerance) return left + right;
  return adaptive_gauss_legendre(f, a, mid, left, 0.5 * tolerance, depth + 1) +
         adaptive_gauss_legendre(f, mid, b, right, 0.5 * tolerance, depth + 1);
}

/// ∫_a^b f with relative error about `relative_tolerance` for smooth f.
template <class F>
double integrate(const F& f, double a, double b, double relative_tolerance = 1e-14) {
  if (a == b) return 0.0;
  const double whole = gauss_legendre(f, a, b);
  const double tolerance = relative_tolerance * std::abs(whole) + 1e-300;
  return adaptive_gauss_legendre(f, a, b, whole, tolerance, 0);
}

/// The angle t in [t0, t1] minimising |(a·cos t, b·sin t) − (x, y)| (ties: the smallest t).
/// a, b ≥ 0 in any order (b = 0 is a segment). Every critical angle is bracketed exactly:
/// between the quadrant angles and the two angles where tan³ t = −b·y / (a·x), the function
/// g(t)/(sin t·cos t) (g = half the derivative of the squared distance) is monotone, so each
/// piece holds at most one root, found by safeguarded Newton.
double ellipse_closest_angle(double a, double b, double x, double y, double t0, double t1);

/// Any unit vector perpendicular to the unit vector `d`.
Vec3 any_perpendicular(const Vec3& d);

}  // namespace csgtile::kernel::detail
