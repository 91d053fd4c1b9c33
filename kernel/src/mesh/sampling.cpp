#include "mesh/sampling.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace csgtile::kernel::detail {

namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;
constexpr int kCurvatureSamples = 64;
constexpr double kCurvatureMargin = 0.95;

std::vector<double> uniform(double first, double last, std::size_t n) {
  std::vector<double> t(n + 1);
  for (std::size_t i = 0; i <= n; ++i) {
    t[i] = first + (last - first) * static_cast<double>(i) / static_cast<double>(n);
  }
  t.back() = last;
  return t;
}

}  // namespace

double allowed_turn(double radius, double chordal, double angular) {
  // Sagitta of an arc turning by θ: radius·(1 − cos(θ/2)).
  const double c = 1.0 - chordal / radius;
  const double turn = c <= -1.0 ? kTwoPi : 2.0 * std::acos(c);
  return std::min(turn, angular);
}

std::size_t segments_for(double span, double step) {
  // The slack keeps an exact fit (span an integer multiple of step) from rounding up.
  if (!(step > 0.0)) return 0;
  const double n = std::ceil(span / step - 1e-9);
  if (!(n <= static_cast<double>(kMaxSegments))) return 0;
  return std::max<std::size_t>(1, static_cast<std::size_t>(n));
}

double uniform_step(const CurveDerivatives& derivatives, double t0, double t1, double chordal,
                    double angular) {
  const double span = t1 - t0;
  double step = span;
  for (int i = 0; i <= kCurvatureSamples; ++i) {
    const auto [d1, d2] = derivatives(t0 + span * i / kCurvatureSamples);
    const double speed2 = d1.squaredNorm();
    const double bend = d1.cross(d2).norm();  // curvature · speed³
    if (!(speed2 > 0.0) || !(bend > 0.0)) continue;
    const double turn_rate = bend / speed2;  // radians per unit parameter
    const double radius = speed2 * std::sqrt(speed2) / bend;
    step = std::min(step, kCurvatureMargin * allowed_turn(radius, chordal, angular) / turn_rate);
  }
  return step;
}

std::vector<double> curve_parameters(const Curve& curve, double first, double last, double chordal,
                                     double angular, double max_step) {
  double step;
  switch (curve.kind()) {
    case CurveKind::Line:
      return {first, last};
    case CurveKind::Polyline: {
      // A polyline is its own chords: its breakpoints in range are all it needs.
      std::vector<double> t{first};
      const auto lowest = static_cast<long long>(std::floor(first)) + 1;
      for (long long k = lowest; static_cast<double>(k) < last; ++k) {
        if (static_cast<double>(k) > first) t.push_back(static_cast<double>(k));
      }
      t.push_back(last);
      return t;
    }
    case CurveKind::Circle:
      step = allowed_turn(static_cast<const CircleCurve&>(curve).radius(), chordal, angular);
      break;
    default:
      step = uniform_step(
          [&](double t) { return std::make_pair(curve.derivative(t), curve.second_derivative(t)); },
          first, last, chordal, angular);
      break;
  }
  const std::size_t n = segments_for(last - first, std::min(step, max_step));
  if (n == 0) return {};
  return uniform(first, last, n);
}

bool revolution_like(const Surface& surface) {
  switch (surface.kind()) {
    case SurfaceKind::Cylinder:
    case SurfaceKind::Cone:
    case SurfaceKind::Sphere:
    case SurfaceKind::Torus:
    case SurfaceKind::Revolution:
      return true;
    default:
      return false;
  }
}

double row_step(const Surface& surface, double v, double u0, double u1, double chordal,
                double angular) {
  if (revolution_like(surface)) {
    const double radius = surface.du(u0, v).norm();
    return radius > 0.0 ? allowed_turn(radius, chordal, angular) : std::abs(u1 - u0);
  }
  const double h = 1e-5 * std::max(1.0, std::abs(u1 - u0));
  return uniform_step(
      [&](double u) {
        const Vec3 d2 = (surface.du(u + h, v) - surface.du(u - h, v)) / (2.0 * h);
        return std::make_pair(surface.du(u, v), d2);
      },
      u0, u1, chordal, angular);
}

std::size_t row_segment_count(const Surface& surface, double v, double u0, double u1,
                              double chordal, double angular) {
  return segments_for(u1 - u0, row_step(surface, v, u0, u1, chordal, angular));
}

}  // namespace csgtile::kernel::detail
