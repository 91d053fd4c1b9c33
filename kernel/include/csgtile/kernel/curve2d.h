#pragma once
/// \file
/// Curves in a surface's (u, v) parameter plane ("pcurves"). A face stores one for every
/// edge use, parametrised like the edge's 3D curve: pcurve(t) is the (u, v) of C(t).

#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include "csgtile/kernel/location.h"

namespace csgtile::kernel {

enum class Curve2dKind : std::uint8_t { Line = 0, Circle = 1, Polyline = 2 };

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

}  // namespace csgtile::kernel
