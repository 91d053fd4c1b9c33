#pragma once
/// \file
/// Surfaces (paper Table 4): plane, cylinder, cone, sphere, torus, linear extrusion and
/// revolution, with the paper's parametrisations. Immutable, shared through SurfacePtr.
/// The normal is N = ∂S/∂u × ∂S/∂v normalised; for the closed quadrics it points away from
/// the axis/centre (outward).

#include <memory>

#include "csgtile/kernel/bounding_box.h"
#include "csgtile/kernel/curve.h"
#include "csgtile/kernel/frame.h"

namespace csgtile::kernel {

enum class SurfaceKind : std::uint8_t {
  Plane = 0,
  Cylinder = 1,
  Cone = 2,
  Sphere = 3,
  Torus = 4,
  Extrusion = 5,
  Revolution = 6
};

/// A rectangle of the (u, v) parameter plane.
struct ParamBox {
  double u0, u1, v0, v1;
};

class Surface;
using SurfacePtr = std::shared_ptr<const Surface>;

class Surface {
 public:
  virtual ~Surface() = default;
  virtual SurfaceKind kind() const = 0;
  virtual Vec3 point(double u, double v) const = 0;
  virtual Vec3 du(double u, double v) const = 0;
  virtual Vec3 dv(double u, double v) const = 0;
  /// Unit normal ∂S/∂u × ∂S/∂v / |…|; at a singular point (sphere pole, cone apex) the
  /// limit along v, so it is always defined.
  virtual Vec3 normal(double u, double v) const;
  /// Period in u (2π for the quadrics and revolutions) or 0; likewise in v (2π for torus).
  virtual double u_period() const { return 0.0; }
  virtual double v_period() const { return 0.0; }
  /// (u, v) of the surface point closest to p. Periodic parameters are returned in
  /// [0, period); the sphere's v in [-π/2, π/2].
  virtual Vec2 closest_parameters(const Vec3& p) const = 0;
  /// Exact bounding box of the patch S(box).
  virtual BoundingBox bounds(const ParamBox& box) const = 0;
  /// The same surface moved by a location. Angle parameters are kept; parameters that are
  /// lengths scale with s = loc.scale(): plane u and v, cylinder/cone/extrusion v, and
  /// whatever the basis (extrusion u) or meridian (revolution v) curve scales (a line's t).
  /// E.g. for a cylinder transformed(loc)->point(u, s·v) == loc(S(u, v)); for a sphere
  /// ->point(u, v) == loc(S(u, v)). Radii are multiplied by s.
  virtual SurfacePtr transformed(const Location& loc) const = 0;
};

/// S(u,v) = O + u·X + v·Y; normal Z.
class PlaneSurface final : public Surface {
 public:
  explicit PlaneSurface(const Frame& frame) : frame_(frame) {}
  SurfaceKind kind() const override { return SurfaceKind::Plane; }
  const Frame& frame() const { return frame_; }
  Vec3 point(double u, double v) const override;
  Vec3 du(double u, double v) const override;
  Vec3 dv(double u, double v) const override;
  Vec3 normal(double u, double v) const override;
  Vec2 closest_parameters(const Vec3& p) const override;
  BoundingBox bounds(const ParamBox& box) const override;
  SurfacePtr transformed(const Location& loc) const override;

 private:
  Frame frame_;
};

/// S(u,v) = O + r·(cos u·X + sin u·Y) + v·Z.
class CylinderSurface final : public Surface {
 public:
  CylinderSurface(const Frame& frame, double radius) : frame_(frame), radius_(radius) {}
  SurfaceKind kind() const override { return SurfaceKind::Cylinder; }
  const Frame& frame() const { return frame_; }
  double radius() const { return radius_; }
  Vec3 point(double u, double v) const override;
  Vec3 du(double u, double v) const override;
  Vec3 dv(double u, double v) const override;
  double u_period() const override;
  Vec2 closest_parameters(const Vec3& p) const override;
  BoundingBox bounds(const ParamBox& box) const override;
  SurfacePtr transformed(const Location& loc) const override;

 private:
  Frame frame_;
  double radius_;
};

/// S(u,v) = O + (r + v·sin φ)·(cos u·X + sin u·Y) + v·cos φ·Z, φ in (-π/2, π/2) the
/// semi-angle, r the radius at v = 0. The apex is at v = -r / sin φ.
class ConeSurface final : public Surface {
 public:
  ConeSurface(const Frame& frame, double reference_radius, double semi_angle)
      : frame_(frame), radius_(reference_radius), semi_angle_(semi_angle) {}
  SurfaceKind kind() const override { return SurfaceKind::Cone; }
  const Frame& frame() const { return frame_; }
  double reference_radius() const { return radius_; }
  double semi_angle() const { return semi_angle_; }
  Vec3 point(double u, double v) const override;
  Vec3 du(double u, double v) const override;
  Vec3 dv(double u, double v) const override;
  Vec3 normal(double u, double v) const override;
  double u_period() const override;
  Vec2 closest_parameters(const Vec3& p) const override;
  BoundingBox bounds(const ParamBox& box) const override;
  SurfacePtr transformed(const Location& loc) const override;

 private:
  Frame frame_;
  double radius_, semi_angle_;
};

/// S(u,v) = O + r·cos v·(cos u·X + sin u·Y) + r·sin v·Z, v in [-π/2, π/2].
class SphereSurface final : public Surface {
 public:
  SphereSurface(const Frame& frame, double radius) : frame_(frame), radius_(radius) {}
  SurfaceKind kind() const override { return SurfaceKind::Sphere; }
  const Frame& frame() const { return frame_; }
  double radius() const { return radius_; }
  Vec3 point(double u, double v) const override;
  Vec3 du(double u, double v) const override;
  Vec3 dv(double u, double v) const override;
  Vec3 normal(double u, double v) const override;
  double u_period() const override;
  Vec2 closest_parameters(const Vec3& p) const override;
  BoundingBox bounds(const ParamBox& box) const override;
  SurfacePtr transformed(const Location& loc) const override;

 private:
  Frame frame_;
  double radius_;
};

/// S(u,v) = O + (R + r·cos v)·(cos u·X + sin u·Y) + r·sin v·Z, R > r > 0.
class TorusSurface final : public Surface {
 public:
  TorusSurface(const Frame& frame, double major_radius, double minor_radius)
      : frame_(frame), major_(major_radius), minor_(minor_radius) {}
  SurfaceKind kind() const override { return SurfaceKind::Torus; }
  const Frame& frame() const { return frame_; }
  double major_radius() const { return major_; }
  double minor_radius() const { return minor_; }
  Vec3 point(double u, double v) const override;
  Vec3 du(double u, double v) const override;
  Vec3 dv(double u, double v) const override;
  double u_period() const override;
  double v_period() const override;
  Vec2 closest_parameters(const Vec3& p) const override;
  BoundingBox bounds(const ParamBox& box) const override;
  SurfacePtr transformed(const Location& loc) const override;

 private:
  Frame frame_;
  double major_, minor_;
};

/// S(u,v) = C(u) + v·D, |D| = 1 (surface of linear extrusion).
class ExtrusionSurface final : public Surface {
 public:
  ExtrusionSurface(CurvePtr basis, const Vec3& direction);  // direction normalised here
  SurfaceKind kind() const override { return SurfaceKind::Extrusion; }
  const CurvePtr& basis() const { return basis_; }
  const Vec3& direction() const { return direction_; }
  Vec3 point(double u, double v) const override;
  Vec3 du(double u, double v) const override;
  Vec3 dv(double u, double v) const override;
  double u_period() const override { return basis_->period(); }
  Vec2 closest_parameters(const Vec3& p) const override;
  BoundingBox bounds(const ParamBox& box) const override;
  SurfacePtr transformed(const Location& loc) const override;

 private:
  CurvePtr basis_;
  Vec3 direction_;
};

/// Surface of revolution of a meridian curve C about the axis (P, D), |D| = 1:
/// S(u,v) = P + V_D(v) + cos u·(V(v) − V_D(v)) + sin u·(D × V(v)), where V(v) = C(v) − P
/// and V_D(v) = (V·D)·D (the paper's Table 4). Precondition: C lies in one half-plane
/// bounded by the axis (coplanar with it).
class RevolutionSurface final : public Surface {
 public:
  RevolutionSurface(CurvePtr meridian, const Vec3& axis_origin, const Vec3& axis_direction);
  SurfaceKind kind() const override { return SurfaceKind::Revolution; }
  const CurvePtr& meridian() const { return meridian_; }
  const Vec3& axis_origin() const { return origin_; }
  const Vec3& axis_direction() const { return direction_; }
  Vec3 point(double u, double v) const override;
  Vec3 du(double u, double v) const override;
  Vec3 dv(double u, double v) const override;
  /// Also defined where the meridian meets the axis (the limit along v from the side of
  /// the meridian's half-plane).
  Vec3 normal(double u, double v) const override;
  double u_period() const override;
  Vec2 closest_parameters(const Vec3& p) const override;
  BoundingBox bounds(const ParamBox& box) const override;
  SurfacePtr transformed(const Location& loc) const override;

 private:
  CurvePtr meridian_;
  Vec3 origin_, direction_;
  /// Unit vector ⊥ direction_ in the meridian's plane, towards the meridian (cached).
  Vec3 radial_;
};

}  // namespace csgtile::kernel
