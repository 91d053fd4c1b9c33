#pragma once
/// \file
/// 3D curves (paper Table 4): line, circle, ellipse, and a tolerance-bounded polyline that
/// approximates general intersection curves. Curves are immutable and shared through
/// CurvePtr; a curve is infinite or periodic, an edge restricts it to [t0, t1].

#include <cstdint>
#include <memory>
#include <vector>

#include "csgtile/kernel/bounding_box.h"
#include "csgtile/kernel/frame.h"

namespace csgtile::kernel {

enum class CurveKind : std::uint8_t { Line = 0, Circle = 1, Ellipse = 2, Polyline = 3, Trig = 4 };

class Curve;
using CurvePtr = std::shared_ptr<const Curve>;

/// Parametric curve C(t).
class Curve {
 public:
  virtual ~Curve() = default;
  virtual CurveKind kind() const = 0;
  virtual Vec3 point(double t) const = 0;
  /// dC/dt.
  virtual Vec3 derivative(double t) const = 0;
  /// d²C/dt² (zero for lines and on polyline segments).
  virtual Vec3 second_derivative(double t) const = 0;
  /// 2π for circles and ellipses, 0 for non-periodic curves.
  virtual double period() const { return 0.0; }
  /// Natural parameter range when the curve is bounded (polyline), else (-inf, inf) or
  /// [0, period).
  virtual double first_parameter() const;
  virtual double last_parameter() const;
  /// Parameter in [t0, t1] of the point of the arc closest to p (ties: the smallest t).
  virtual double closest_parameter(const Vec3& p, double t0, double t1) const = 0;
  /// Maximum of dot(C(t), w) over t in [t0, t1] (the arc's support function). Exact.
  virtual double support(const Vec3& w, double t0, double t1) const = 0;
  /// Exact bounding box of the arc [t0, t1] (from support along ±x, ±y, ±z).
  BoundingBox bounds(double t0, double t1) const;
  /// The same curve moved by a location. Parameters that are angles (circle, ellipse) or
  /// vertex indices (polyline) are kept: transformed(loc)->point(t) == loc(C(t)). A parameter
  /// that is a length (LineCurve's arc length) scales with s = loc.scale():
  /// transformed(loc)->point(s·t) == loc(C(t)).
  virtual CurvePtr transformed(const Location& loc) const = 0;
  /// Length of the arc [t0, t1] (closed form for line and circle, quadrature otherwise,
  /// relative error below 1e-12).
  virtual double length(double t0, double t1) const;
};

/// C(t) = origin + t·direction, |direction| = 1, t is arc length.
class LineCurve final : public Curve {
 public:
  LineCurve(const Vec3& origin, const Vec3& direction);  // direction normalised here
  CurveKind kind() const override { return CurveKind::Line; }
  const Vec3& origin() const { return origin_; }
  const Vec3& direction() const { return direction_; }
  Vec3 point(double t) const override { return origin_ + t * direction_; }
  Vec3 derivative(double) const override { return direction_; }
  Vec3 second_derivative(double) const override { return Vec3::Zero(); }
  double closest_parameter(const Vec3& p, double t0, double t1) const override;
  double support(const Vec3& w, double t0, double t1) const override;
  /// The direction stays unit, so t (arc length) scales: result->point(s·t) == loc(C(t)).
  CurvePtr transformed(const Location& loc) const override;
  double length(double t0, double t1) const override;

 private:
  Vec3 origin_, direction_;
};

/// C(t) = O + r·(cos t·X + sin t·Y) in `frame`; period 2π.
class CircleCurve final : public Curve {
 public:
  CircleCurve(const Frame& frame, double radius);
  CurveKind kind() const override { return CurveKind::Circle; }
  const Frame& frame() const { return frame_; }
  double radius() const { return radius_; }
  Vec3 point(double t) const override;
  Vec3 derivative(double t) const override;
  Vec3 second_derivative(double t) const override;
  double period() const override;
  double closest_parameter(const Vec3& p, double t0, double t1) const override;
  double support(const Vec3& w, double t0, double t1) const override;
  CurvePtr transformed(const Location& loc) const override;
  double length(double t0, double t1) const override;

 private:
  Frame frame_;
  double radius_;
};

/// C(t) = O + a·cos t·X + b·sin t·Y with a ≥ b > 0 (major radius along X); period 2π.
class EllipseCurve final : public Curve {
 public:
  EllipseCurve(const Frame& frame, double major_radius, double minor_radius);
  CurveKind kind() const override { return CurveKind::Ellipse; }
  const Frame& frame() const { return frame_; }
  double major_radius() const { return major_; }
  double minor_radius() const { return minor_; }
  Vec3 point(double t) const override;
  Vec3 derivative(double t) const override;
  Vec3 second_derivative(double t) const override;
  double period() const override;
  double closest_parameter(const Vec3& p, double t0, double t1) const override;
  double support(const Vec3& w, double t0, double t1) const override;
  CurvePtr transformed(const Location& loc) const override;

 private:
  Frame frame_;
  double major_, minor_;
};

/// Piecewise-linear curve through points P0..Pn, parameter t in [0, n] (segment i is
/// t ∈ [i, i+1]). `tolerance` is the maximum distance from the exact curve it approximates
/// (0 when it is exact), and becomes the lower bound of the tolerance of edges that use it.
class PolylineCurve final : public Curve {
 public:
  /// Precondition: at least two points.
  PolylineCurve(std::vector<Vec3> points, double tolerance);
  CurveKind kind() const override { return CurveKind::Polyline; }
  const std::vector<Vec3>& points() const { return points_; }
  double tolerance() const { return tolerance_; }
  Vec3 point(double t) const override;
  Vec3 derivative(double t) const override;
  Vec3 second_derivative(double) const override { return Vec3::Zero(); }
  double first_parameter() const override { return 0.0; }
  double last_parameter() const override { return static_cast<double>(points_.size() - 1); }
  double closest_parameter(const Vec3& p, double t0, double t1) const override;
  double support(const Vec3& w, double t0, double t1) const override;
  CurvePtr transformed(const Location& loc) const override;
  double length(double t0, double t1) const override;

 private:
  std::vector<Vec3> points_;
  double tolerance_;
};

/// C(t) = c + cos t·a + sin t·b: an ellipse given by two conjugate semi-diameters a, b
/// (a circle when |a| = |b| and a ⊥ b), period 2π. Boolean section curves use it so that
/// the curve's parameter is the natural angle of the surfaces it lies on (a plane section of
/// a cylinder parametrised by the cylinder's angle), which keeps their pcurves exact
/// (Trig2d). Precondition: a × b ≠ 0.
class TrigCurve final : public Curve {
 public:
  TrigCurve(const Vec3& center, const Vec3& a, const Vec3& b) : center_(center), a_(a), b_(b) {}
  CurveKind kind() const override { return CurveKind::Trig; }
  const Vec3& center() const { return center_; }
  const Vec3& a() const { return a_; }
  const Vec3& b() const { return b_; }
  Vec3 point(double t) const override;
  Vec3 derivative(double t) const override;
  Vec3 second_derivative(double t) const override;
  double period() const override;
  double closest_parameter(const Vec3& p, double t0, double t1) const override;
  double support(const Vec3& w, double t0, double t1) const override;
  CurvePtr transformed(const Location& loc) const override;

 private:
  Vec3 center_, a_, b_;
};

}  // namespace csgtile::kernel
