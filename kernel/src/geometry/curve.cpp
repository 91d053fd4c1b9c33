#include "csgtile/kernel/curve.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <utility>

#include "geometry/geometry_internal.h"

namespace csgtile::kernel {

namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

/// Index of the polyline segment holding parameter t, clamped to the valid segments so that
/// parameters outside [0, n] extrapolate the end segments.
std::size_t segment_index(double t, std::size_t segment_count) {
  const double i = std::clamp(std::floor(t), 0.0, static_cast<double>(segment_count - 1));
  return static_cast<std::size_t>(i);
}

/// Best candidate of a minimisation. Offered in ascending t, a candidate must beat the best
/// by more than `tie` (rounding noise of the distances), so the smallest t wins ties as the
/// Curve contract asks.
struct ClosestCandidate {
  double t = 0.0;
  double distance2 = kInfinity;
  double tie = 0.0;
  void offer(double candidate_t, double candidate_distance2) {
    if (candidate_distance2 < distance2 - tie) {
      t = candidate_t;
      distance2 = candidate_distance2;
    }
  }
};

}  // namespace

// ---- detail -------------------------------------------------------------------------------

namespace detail {

const GaussLegendreRule& gauss_legendre_rule() {
  // Function-local static: computed once, thread-safe initialisation.
  static const GaussLegendreRule rule = [] {
    GaussLegendreRule r;
    constexpr int kN = GaussLegendreRule::kOrder;
    for (int i = 0; i < kN; ++i) {
      // Classical starting guess for the i-th root of P_n; Newton converges in a few steps.
      double x = std::cos(kPi * (i + 0.75) / (kN + 0.5));
      double derivative = 1.0;
      for (int iteration = 0; iteration < 100; ++iteration) {
        double p0 = 1.0;
        double p1 = x;
        for (int k = 1; k < kN; ++k) {
          const double p2 = ((2.0 * k + 1.0) * x * p1 - k * p0) / (k + 1.0);
          p0 = p1;
          p1 = p2;
        }
        derivative = kN * (x * p1 - p0) / (x * x - 1.0);
        const double step = p1 / derivative;
        x -= step;
        if (std::abs(step) < 1e-17) break;
      }
      // Recompute P_n' at the converged root for the weight.
      double p0 = 1.0;
      double p1 = x;
      for (int k = 1; k < kN; ++k) {
        const double p2 = ((2.0 * k + 1.0) * x * p1 - k * p0) / (k + 1.0);
        p0 = p1;
        p1 = p2;
      }
      derivative = kN * (x * p1 - p0) / (x * x - 1.0);
      const auto index = static_cast<std::size_t>(i);
      r.nodes[index] = x;
      r.weights[index] = 2.0 / ((1.0 - x * x) * derivative * derivative);
    }
    return r;
  }();
  return rule;
}

double ellipse_closest_angle(double a, double b, double x, double y, double t0, double t1) {
  if (t1 < t0) std::swap(t0, t1);
  const auto distance2 = [&](double t) {
    const double dx = a * std::cos(t) - x;
    const double dy = b * std::sin(t) - y;
    return dx * dx + dy * dy;
  };
  // g = ½ d/dt distance², and its derivative.
  const double k = b * b - a * a;
  const auto g = [&](double t) {
    const double s = std::sin(t);
    const double c = std::cos(t);
    return k * s * c + a * x * s - b * y * c;
  };
  const auto dg = [&](double t) {
    return k * std::cos(2.0 * t) + a * x * std::cos(t) + b * y * std::sin(t);
  };
  // Values of g below this are rounding noise (its terms are at most this large).
  const double noise = 1e-14 * (std::abs(k) + std::abs(a * x) + std::abs(b * y));

  // Piece boundaries over one period: the quadrant angles and where tan³ t = −b·y/(a·x).
  std::array<double, 7> breaks{0.0, 0.5 * kPi, kPi, 1.5 * kPi, kTwoPi, 0.0, 0.0};
  const double turn = std::atan2(std::cbrt(-b * y), std::cbrt(a * x));
  breaks[5] = wrap_two_pi(turn);
  breaks[6] = wrap_two_pi(turn + kPi);
  std::sort(breaks.begin(), breaks.end());

  std::array<double, 14> critical{};
  std::size_t critical_count = 0;
  for (double t : breaks) critical[critical_count++] = t;

  const auto sign = [](double v) { return v > 0.0 ? 1 : (v < 0.0 ? -1 : 0); };
  for (std::size_t i = 0; i + 1 < breaks.size(); ++i) {
    const double lo0 = breaks[i];
    const double hi0 = breaks[i + 1];
    if (!(hi0 > lo0)) continue;
    // Sign of g just inside each end; where g vanishes at the end (to rounding) the sign
    // inside follows from g' there.
    const double g_lo = g(lo0);
    const double g_hi = g(hi0);
    const int s_lo = std::abs(g_lo) > noise ? sign(g_lo) : sign(dg(lo0));
    const int s_hi = std::abs(g_hi) > noise ? sign(g_hi) : -sign(dg(hi0));
    if (s_lo == 0 || s_hi == 0 || s_lo == s_hi) continue;
    // Safeguarded Newton: keeps a bracket [lo, hi] with sign s_lo at lo.
    double lo = lo0;
    double hi = hi0;
    double t = 0.5 * (lo + hi);
    for (int iteration = 0; iteration < 100; ++iteration) {
      const double gt = g(t);
      if (gt == 0.0) break;
      if (sign(gt) == s_lo) {
        lo = t;
      } else {
        hi = t;
      }
      const double d = dg(t);
      double next = d != 0.0 ? t - gt / d : lo;
      if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
      const bool converged = std::abs(next - t) <= 1e-16 * (1.0 + std::abs(t));
      t = next;
      if (converged || hi - lo <= 1e-16) break;
    }
    critical[critical_count++] = t;
  }

  ClosestCandidate best;
  const double extent = std::max(a, b) + std::abs(x) + std::abs(y);
  best.tie = 1e-15 * extent * extent;
  std::array<double, 16> candidates{};
  std::size_t candidate_count = 0;
  candidates[candidate_count++] = t0;
  candidates[candidate_count++] = t1;
  for (std::size_t i = 0; i < critical_count; ++i) {
    // Only the first occurrence in the range matters: later ones repeat the distance.
    const double t = first_angle_at_or_after(critical[i], t0);
    if (t <= t1) candidates[candidate_count++] = t;
  }
  std::sort(candidates.begin(), candidates.begin() + static_cast<std::ptrdiff_t>(candidate_count));
  for (std::size_t i = 0; i < candidate_count; ++i) {
    best.offer(candidates[i], distance2(candidates[i]));
  }
  // Polish: a root next to a piece boundary may only be represented by the boundary itself;
  // Newton from there converges to it. Steps are kept only when they stay in range and do
  // not increase the distance.
  double t = best.t;
  double d2 = best.distance2;
  for (int iteration = 0; iteration < 8; ++iteration) {
    const double d = dg(t);
    if (d == 0.0) break;
    const double next = t - g(t) / d;
    if (!(next >= t0 && next <= t1)) break;
    const double next_d2 = distance2(next);
    if (next_d2 > d2) break;
    const bool converged = std::abs(next - t) <= 1e-16 * (1.0 + std::abs(t));
    t = next;
    d2 = next_d2;
    if (converged) break;
  }
  return t;
}

}  // namespace detail

// ---- Curve --------------------------------------------------------------------------------

double Curve::first_parameter() const { return period() > 0.0 ? 0.0 : -kInfinity; }

double Curve::last_parameter() const { return period() > 0.0 ? period() : kInfinity; }

BoundingBox Curve::bounds(double t0, double t1) const {
  BoundingBox box;
  for (int i = 0; i < 3; ++i) {
    const Vec3 axis = Vec3::Unit(i);
    box.max[i] = support(axis, t0, t1);
    box.min[i] = -support(-axis, t0, t1);
  }
  return box;
}

double Curve::length(double t0, double t1) const {
  if (t1 < t0) std::swap(t0, t1);
  if (!std::isfinite(t0) || !std::isfinite(t1)) return kInfinity;
  const auto speed = [this](double t) { return derivative(t).norm(); };
  if (period() <= 0.0) return detail::integrate(speed, t0, t1);
  // Periodic curves: the speed of a conic peaks and dips at multiples of π/2, so pieces
  // ending there are smooth and need few subdivisions even for eccentric ellipses.
  constexpr double kQuarter = 0.5 * detail::kPi;
  double total = 0.0;
  double a = t0;
  while (a < t1) {
    double b = (std::floor(a / kQuarter) + 1.0) * kQuarter;
    if (b <= a) b = a + kQuarter;  // floor rounding at a multiple
    b = std::min(b, t1);
    total += detail::integrate(speed, a, b);
    a = b;
  }
  return total;
}

// ---- LineCurve ----------------------------------------------------------------------------

LineCurve::LineCurve(const Vec3& origin, const Vec3& direction)
    : origin_(origin), direction_(direction.normalized()) {}

double LineCurve::closest_parameter(const Vec3& p, double t0, double t1) const {
  if (t1 < t0) std::swap(t0, t1);
  return std::clamp((p - origin_).dot(direction_), t0, t1);
}

double LineCurve::support(const Vec3& w, double t0, double t1) const {
  const double slope = direction_.dot(w);
  return detail::linear_range(slope, origin_.dot(w), t0, t1).max;
}

CurvePtr LineCurve::transformed(const Location& loc) const {
  // The direction stays unit, so arc length (the parameter) scales with loc.scale().
  return std::make_shared<LineCurve>(loc.apply_point(origin_), loc.apply_direction(direction_));
}

double LineCurve::length(double t0, double t1) const { return std::abs(t1 - t0); }

// ---- CircleCurve --------------------------------------------------------------------------

CircleCurve::CircleCurve(const Frame& frame, double radius) : frame_(frame), radius_(radius) {}

Vec3 CircleCurve::point(double t) const {
  return frame_.origin + radius_ * (std::cos(t) * frame_.x + std::sin(t) * frame_.y);
}

Vec3 CircleCurve::derivative(double t) const {
  return radius_ * (-std::sin(t) * frame_.x + std::cos(t) * frame_.y);
}

Vec3 CircleCurve::second_derivative(double t) const {
  return -radius_ * (std::cos(t) * frame_.x + std::sin(t) * frame_.y);
}

double CircleCurve::period() const { return detail::kTwoPi; }

double CircleCurve::closest_parameter(const Vec3& p, double t0, double t1) const {
  if (t1 < t0) std::swap(t0, t1);
  const Vec3 q = p - frame_.origin;
  const double x = q.dot(frame_.x);
  const double y = q.dot(frame_.y);
  // On the axis every point of the circle is equally close: the smallest t wins.
  if (x == 0.0 && y == 0.0) return t0;
  const double angle = std::atan2(y, x);
  const double t = detail::first_angle_at_or_after(angle, t0);
  if (t <= t1) return t;
  // Outside the arc the distance grows with the angular distance from `angle`, so the
  // nearer endpoint in angle is the closer one (larger cosine = smaller distance).
  const double c0 = std::cos(t0 - angle);
  const double c1 = std::cos(t1 - angle);
  return c1 > c0 ? t1 : t0;
}

double CircleCurve::support(const Vec3& w, double t0, double t1) const {
  return frame_.origin.dot(w) +
         detail::trig_range(radius_ * frame_.x.dot(w), radius_ * frame_.y.dot(w), t0, t1).max;
}

CurvePtr CircleCurve::transformed(const Location& loc) const {
  return std::make_shared<CircleCurve>(frame_.transformed(loc), radius_ * loc.scale());
}

double CircleCurve::length(double t0, double t1) const { return radius_ * std::abs(t1 - t0); }

// ---- EllipseCurve -------------------------------------------------------------------------

EllipseCurve::EllipseCurve(const Frame& frame, double major_radius, double minor_radius)
    : frame_(frame), major_(major_radius), minor_(minor_radius) {}

Vec3 EllipseCurve::point(double t) const {
  return frame_.origin + major_ * std::cos(t) * frame_.x + minor_ * std::sin(t) * frame_.y;
}

Vec3 EllipseCurve::derivative(double t) const {
  return -major_ * std::sin(t) * frame_.x + minor_ * std::cos(t) * frame_.y;
}

Vec3 EllipseCurve::second_derivative(double t) const {
  return -major_ * std::cos(t) * frame_.x - minor_ * std::sin(t) * frame_.y;
}

double EllipseCurve::period() const { return detail::kTwoPi; }

double EllipseCurve::closest_parameter(const Vec3& p, double t0, double t1) const {
  const Vec3 q = p - frame_.origin;
  // The component along the frame's z adds a constant to the squared distance.
  return detail::ellipse_closest_angle(major_, minor_, q.dot(frame_.x), q.dot(frame_.y), t0, t1);
}

double EllipseCurve::support(const Vec3& w, double t0, double t1) const {
  return frame_.origin.dot(w) +
         detail::trig_range(major_ * frame_.x.dot(w), minor_ * frame_.y.dot(w), t0, t1).max;
}

CurvePtr EllipseCurve::transformed(const Location& loc) const {
  return std::make_shared<EllipseCurve>(frame_.transformed(loc), major_ * loc.scale(),
                                        minor_ * loc.scale());
}

// ---- PolylineCurve ------------------------------------------------------------------------

PolylineCurve::PolylineCurve(std::vector<Vec3> points, double tolerance)
    : points_(std::move(points)), tolerance_(tolerance) {}

Vec3 PolylineCurve::point(double t) const {
  const std::size_t i = segment_index(t, points_.size() - 1);
  const double s = t - static_cast<double>(i);
  // (1 − s)·P_i + s·P_{i+1} reproduces the vertices exactly at s = 0 and s = 1.
  return (1.0 - s) * points_[i] + s * points_[i + 1];
}

Vec3 PolylineCurve::derivative(double t) const {
  const std::size_t i = segment_index(t, points_.size() - 1);
  return points_[i + 1] - points_[i];
}

double PolylineCurve::closest_parameter(const Vec3& p, double t0, double t1) const {
  const double n = last_parameter();
  double lo = std::clamp(t0, 0.0, n);
  double hi = std::clamp(t1, 0.0, n);
  if (hi < lo) std::swap(lo, hi);
  ClosestCandidate best;
  const std::size_t first = segment_index(lo, points_.size() - 1);
  const std::size_t last = segment_index(hi, points_.size() - 1);
  for (std::size_t i = first; i <= last; ++i) {
    const double a = std::max(lo, static_cast<double>(i));
    const double b = std::min(hi, static_cast<double>(i + 1));
    const Vec3 d = points_[i + 1] - points_[i];
    const double dd = d.squaredNorm();
    double t = a;
    if (dd > 0.0) {
      t = std::clamp(static_cast<double>(i) + (p - points_[i]).dot(d) / dd, a, b);
    }
    best.offer(t, (point(t) - p).squaredNorm());
  }
  return best.t;
}

double PolylineCurve::support(const Vec3& w, double t0, double t1) const {
  if (t1 < t0) std::swap(t0, t1);
  // Linear on each segment: the maximum is at the ends of the range or at a vertex.
  double best = std::max(point(t0).dot(w), point(t1).dot(w));
  const double n = last_parameter();
  const double first = std::max(std::floor(t0) + 1.0, 1.0);
  const double last = std::min(std::ceil(t1) - 1.0, n - 1.0);
  for (double k = first; k <= last; k += 1.0) {
    best = std::max(best, points_[static_cast<std::size_t>(k)].dot(w));
  }
  return best;
}

CurvePtr PolylineCurve::transformed(const Location& loc) const {
  std::vector<Vec3> moved;
  moved.reserve(points_.size());
  for (const Vec3& p : points_) moved.push_back(loc.apply_point(p));
  return std::make_shared<PolylineCurve>(std::move(moved), tolerance_ * loc.scale());
}

double PolylineCurve::length(double t0, double t1) const {
  const double n = last_parameter();
  double lo = std::clamp(t0, 0.0, n);
  double hi = std::clamp(t1, 0.0, n);
  if (hi < lo) std::swap(lo, hi);
  double total = 0.0;
  const std::size_t first = segment_index(lo, points_.size() - 1);
  const std::size_t last = segment_index(hi, points_.size() - 1);
  for (std::size_t i = first; i <= last; ++i) {
    const double a = std::max(lo, static_cast<double>(i));
    const double b = std::min(hi, static_cast<double>(i + 1));
    if (b > a) total += (b - a) * (points_[i + 1] - points_[i]).norm();
  }
  return total;
}

}  // namespace csgtile::kernel

// ---- TrigCurve ---------------------------------------------------------------------------

namespace csgtile::kernel {

Vec3 TrigCurve::point(double t) const { return center_ + std::cos(t) * a_ + std::sin(t) * b_; }
Vec3 TrigCurve::derivative(double t) const { return -std::sin(t) * a_ + std::cos(t) * b_; }
Vec3 TrigCurve::second_derivative(double t) const { return -std::cos(t) * a_ - std::sin(t) * b_; }
double TrigCurve::period() const { return detail::kTwoPi; }

double TrigCurve::closest_parameter(const Vec3& p, double t0, double t1) const {
  // Principal axes: with t = s + θ, C = c + cos s·A + sin s·B where A = a cos θ + b sin θ and
  // B = −a sin θ + b cos θ are perpendicular when tan 2θ = 2 a·b / (|a|² − |b|²).
  const double theta = 0.5 * std::atan2(2.0 * a_.dot(b_), a_.squaredNorm() - b_.squaredNorm());
  const Vec3 major = std::cos(theta) * a_ + std::sin(theta) * b_;
  const Vec3 minor = -std::sin(theta) * a_ + std::cos(theta) * b_;
  const double ra = major.norm(), rb = minor.norm();
  const Vec3 q = p - center_;
  const double x = ra > 0 ? q.dot(major) / ra : 0.0;
  const double y = rb > 0 ? q.dot(minor) / rb : 0.0;
  return detail::ellipse_closest_angle(ra, rb, x, y, t0 - theta, t1 - theta) + theta;
}

double TrigCurve::support(const Vec3& w, double t0, double t1) const {
  return center_.dot(w) + detail::trig_range(a_.dot(w), b_.dot(w), t0, t1).max;
}

CurvePtr TrigCurve::transformed(const Location& loc) const {
  return std::make_shared<TrigCurve>(loc.apply_point(center_), loc.apply_vector(a_),
                                     loc.apply_vector(b_));
}

}  // namespace csgtile::kernel
