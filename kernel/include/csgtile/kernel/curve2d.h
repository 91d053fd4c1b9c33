#pragma once
/// \file
/// Curves in a surface's (u, v) parameter plane ("pcurves"). A face stores one for every
/// edge use, parametrised like the edge's 3D curve: pcurve(t) is the (u, v) of C(t).

#include <cmath>
#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include "csgtile/kernel/location.h"

namespace csgtile::kernel {

enum class Curve2dKind : std::uint8_t { Line = 0, Circle = 1, Polyline = 2, Trig = 3 };

class Curve2d;
using Curve2dPtr = std::shared_ptr<const Curve2d>;

class Curve2d {
 public:
  virtual ~Curve2d() = default;
  virtual Curve2dKind kind() const = 0;
  virtual Vec2 point(double t) const = 0;
  virtual Vec2 derivative(double t) const = 0;
};

/// c(t) = origin + t·direction (direction not normalised: it carries the parameter scale).
class Line2d final : public Curve2d {
 public:
  Line2d(const Vec2& origin, const Vec2& direction) : origin_(origin), direction_(direction) {}
  Curve2dKind kind() const override { return Curve2dKind::Line; }
  const Vec2& origin() const { return origin_; }
  const Vec2& direction() const { return direction_; }
  Vec2 point(double t) const override { return origin_ + t * direction_; }
  Vec2 derivative(double) const override { return direction_; }

 private:
  Vec2 origin_, direction_;
};

/// c(t) = center + r·(cos t, sin t)·sense, sense = +1 (counter-clockwise) or -1 (the circle
/// traversed clockwise: c(t) = center + r·(cos t, -sin t)).
class Circle2d final : public Curve2d {
 public:
  Circle2d(const Vec2& center, double radius, int sense = 1)
      : center_(center), radius_(radius), sense_(sense >= 0 ? 1 : -1) {}
  Curve2dKind kind() const override { return Curve2dKind::Circle; }
  const Vec2& center() const { return center_; }
  double radius() const { return radius_; }
  int sense() const { return sense_; }
  Vec2 point(double t) const override;
  Vec2 derivative(double t) const override;

 private:
  Vec2 center_;
  double radius_;
  int sense_;
};

/// Piecewise-linear c(t) through points, t in [0, n] as for PolylineCurve.
class Polyline2d final : public Curve2d {
 public:
  explicit Polyline2d(std::vector<Vec2> points) : points_(std::move(points)) {}
  Curve2dKind kind() const override { return Curve2dKind::Polyline; }
  const std::vector<Vec2>& points() const { return points_; }
  Vec2 point(double t) const override;
  Vec2 derivative(double t) const override;

 private:
  std::vector<Vec2> points_;
};

/// c(t) = c + cos t·a + sin t·b + t·d: the exact pcurve of a TrigCurve or line on a plane,
/// cylinder, cone, sphere or torus whose angular parameter follows the curve's (lines,
/// circles, ellipses, and the sinusoids that plane sections draw on a cylinder).
class Trig2d final : public Curve2d {
 public:
  Trig2d(const Vec2& c, const Vec2& a, const Vec2& b, const Vec2& d) : c_(c), a_(a), b_(b), d_(d) {}
  Curve2dKind kind() const override { return Curve2dKind::Trig; }
  const Vec2& c() const { return c_; }
  const Vec2& a() const { return a_; }
  const Vec2& b() const { return b_; }
  const Vec2& d() const { return d_; }
  Vec2 point(double t) const override { return c_ + std::cos(t) * a_ + std::sin(t) * b_ + t * d_; }
  Vec2 derivative(double t) const override { return -std::sin(t) * a_ + std::cos(t) * b_ + d_; }
  /// The same curve moved by `offset` in the parameter plane (a period shift, say).
  Trig2d shifted(const Vec2& offset) const { return Trig2d(c_ + offset, a_, b_, d_); }

 private:
  Vec2 c_, a_, b_, d_;
};

}  // namespace csgtile::kernel
