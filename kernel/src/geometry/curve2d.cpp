#include "csgtile/kernel/curve2d.h"

#include <algorithm>
#include <cmath>

namespace csgtile::kernel {

namespace {

/// Segment holding t; parameters outside [0, n] extrapolate the end segments, matching
/// PolylineCurve.
std::size_t segment_index(double t, std::size_t segment_count) {
  const double i = std::clamp(std::floor(t), 0.0, static_cast<double>(segment_count - 1));
  return static_cast<std::size_t>(i);
}

}  // namespace

Vec2 Circle2d::point(double t) const {
  return center_ + radius_ * Vec2(std::cos(t), sense_ * std::sin(t));
}

Vec2 Circle2d::derivative(double t) const {
  return radius_ * Vec2(-std::sin(t), sense_ * std::cos(t));
}

Vec2 Polyline2d::point(double t) const {
  // Degenerate inputs (violating the two-point precondition) still give finite answers.
  if (points_.empty()) return Vec2::Zero();
  if (points_.size() == 1) return points_.front();
  const std::size_t i = segment_index(t, points_.size() - 1);
  const double s = t - static_cast<double>(i);
  return (1.0 - s) * points_[i] + s * points_[i + 1];
}

Vec2 Polyline2d::derivative(double t) const {
  if (points_.size() < 2) return Vec2::Zero();
  const std::size_t i = segment_index(t, points_.size() - 1);
  return points_[i + 1] - points_[i];
}

}  // namespace csgtile::kernel
