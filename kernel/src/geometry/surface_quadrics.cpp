#include <cmath>
#include <memory>

#include "csgtile/kernel/surface.h"
#include "geometry/geometry_internal.h"

namespace csgtile::kernel {

namespace {

/// Direction cos u·X + sin u·Y of the frame.
Vec3 radial(const Frame& f, double u) { return std::cos(u) * f.x + std::sin(u) * f.y; }
Vec3 radial_derivative(const Frame& f, double u) { return -std::sin(u) * f.x + std::cos(u) * f.y; }

/// Cylindrical coordinates of p in the frame: polar angle in [0, 2π) (0 on the axis, so that
/// axis points invert deterministically), distance from the axis, height along z.
struct Cylindrical {
  double angle, rho, height;
};
Cylindrical cylindrical(const Frame& f, const Vec3& p) {
  const Vec3 q = p - f.origin;
  const double x = q.dot(f.x);
  const double y = q.dot(f.y);
  const double rho = std::hypot(x, y);
  const double angle = rho > 0.0 ? detail::wrap_two_pi(std::atan2(y, x)) : 0.0;
  return {angle, rho, q.dot(f.z)};
}

}  // namespace

// ---- Surface ------------------------------------------------------------------------------

Vec3 Surface::normal(double u, double v) const {
  // A cross product much shorter than |du|·|dv| is rounding noise at a degenerate point;
  // surfaces with known singularities override normal() with their exact limit, this is the
  // generic fallback: step off the degenerate point, first along v.
  constexpr double kStep = 1e-7;
  const double offsets[][2] = {{0.0, 0.0}, {0.0, kStep}, {0.0, -kStep}, {kStep, 0.0}};
  for (const auto& o : offsets) {
    const Vec3 a = du(u + o[0], v + o[1]);
    const Vec3 b = dv(u + o[0], v + o[1]);
    const Vec3 n = a.cross(b);
    const double len = n.norm();
    if (len > 1e-14 * a.norm() * b.norm() && std::isfinite(len)) return n / len;
  }
  return Vec3::UnitZ();
}

// ---- PlaneSurface -------------------------------------------------------------------------

Vec3 PlaneSurface::point(double u, double v) const {
  return frame_.origin + u * frame_.x + v * frame_.y;
}
Vec3 PlaneSurface::du(double, double) const { return frame_.x; }
Vec3 PlaneSurface::dv(double, double) const { return frame_.y; }
Vec3 PlaneSurface::normal(double, double) const { return frame_.z; }

Vec2 PlaneSurface::closest_parameters(const Vec3& p) const {
  const Vec3 q = p - frame_.origin;
  return {q.dot(frame_.x), q.dot(frame_.y)};
}

BoundingBox PlaneSurface::bounds(const ParamBox& box) const {
  // Affine in (u, v): each coordinate is a sum of two independent linear ranges.
  BoundingBox out;
  for (int i = 0; i < 3; ++i) {
    const detail::ValueRange ru = detail::linear_range(frame_.x[i], 0.0, box.u0, box.u1);
    const detail::ValueRange rv = detail::linear_range(frame_.y[i], 0.0, box.v0, box.v1);
    out.min[i] = frame_.origin[i] + ru.min + rv.min;
    out.max[i] = frame_.origin[i] + ru.max + rv.max;
  }
  return out;
}

SurfacePtr PlaneSurface::transformed(const Location& loc) const {
  // Unit axes: u and v are lengths and scale with loc.scale().
  return std::make_shared<PlaneSurface>(frame_.transformed(loc));
}

// ---- CylinderSurface ----------------------------------------------------------------------

Vec3 CylinderSurface::point(double u, double v) const {
  return frame_.origin + radius_ * radial(frame_, u) + v * frame_.z;
}
Vec3 CylinderSurface::du(double u, double) const { return radius_ * radial_derivative(frame_, u); }
Vec3 CylinderSurface::dv(double, double) const { return frame_.z; }
double CylinderSurface::u_period() const { return detail::kTwoPi; }

Vec2 CylinderSurface::closest_parameters(const Vec3& p) const {
  const Cylindrical c = cylindrical(frame_, p);
  return {c.angle, c.height};
}

BoundingBox CylinderSurface::bounds(const ParamBox& box) const {
  const double r = radius_;
  return detail::rotational_patch_bounds(frame_, box,
                                         [r](double alpha, double beta, double v0, double v1) {
                                           return detail::linear_range(beta, alpha * r, v0, v1);
                                         });
}

SurfacePtr CylinderSurface::transformed(const Location& loc) const {
  return std::make_shared<CylinderSurface>(frame_.transformed(loc), radius_ * loc.scale());
}

// ---- ConeSurface --------------------------------------------------------------------------

Vec3 ConeSurface::point(double u, double v) const {
  return frame_.origin + (radius_ + v * std::sin(semi_angle_)) * radial(frame_, u) +
         v * std::cos(semi_angle_) * frame_.z;
}
Vec3 ConeSurface::du(double u, double v) const {
  return (radius_ + v * std::sin(semi_angle_)) * radial_derivative(frame_, u);
}
Vec3 ConeSurface::dv(double u, double) const {
  return std::sin(semi_angle_) * radial(frame_, u) + std::cos(semi_angle_) * frame_.z;
}
double ConeSurface::u_period() const { return detail::kTwoPi; }

Vec3 ConeSurface::normal(double u, double v) const {
  // du × dv = ρ(v)·(cos φ·e(u) − sin φ·Z) with ρ = r + v·sin φ; at the apex (ρ = 0) this is
  // the limit from the nappe ρ > 0, the valid one.
  const Vec3 n = std::cos(semi_angle_) * radial(frame_, u) - std::sin(semi_angle_) * frame_.z;
  return radius_ + v * std::sin(semi_angle_) < 0.0 ? Vec3(-n) : n;
}

Vec2 ConeSurface::closest_parameters(const Vec3& p) const {
  // The nappe ρ ≥ 0 is a family of rays from the apex; the nearest ray is the one in p's
  // half-plane, and the nearest point on it is the projection clamped to the apex.
  const Cylindrical c = cylindrical(frame_, p);
  const double s = std::sin(semi_angle_);
  double v = (c.rho - radius_) * s + c.height * std::cos(semi_angle_);
  if (radius_ + v * s < 0.0) v = -radius_ / s;
  return {c.angle, v};
}

BoundingBox ConeSurface::bounds(const ParamBox& box) const {
  const double r = radius_;
  const double s = std::sin(semi_angle_);
  const double c = std::cos(semi_angle_);
  // α·(r + v·sin φ) + β·v·cos φ is linear in v.
  return detail::rotational_patch_bounds(
      frame_, box, [r, s, c](double alpha, double beta, double v0, double v1) {
        return detail::linear_range(alpha * s + beta * c, alpha * r, v0, v1);
      });
}

SurfacePtr ConeSurface::transformed(const Location& loc) const {
  return std::make_shared<ConeSurface>(frame_.transformed(loc), radius_ * loc.scale(), semi_angle_);
}

// ---- SphereSurface ------------------------------------------------------------------------

Vec3 SphereSurface::point(double u, double v) const {
  return frame_.origin + radius_ * (std::cos(v) * radial(frame_, u) + std::sin(v) * frame_.z);
}
Vec3 SphereSurface::du(double u, double v) const {
  return radius_ * std::cos(v) * radial_derivative(frame_, u);
}
Vec3 SphereSurface::dv(double u, double v) const {
  return radius_ * (-std::sin(v) * radial(frame_, u) + std::cos(v) * frame_.z);
}
double SphereSurface::u_period() const { return detail::kTwoPi; }

Vec3 SphereSurface::normal(double u, double v) const {
  // du × dv = r²·cos v·(outward unit): exact and defined at the poles (limit from
  // |v| < π/2). Past a pole (cos v < 0) the parametrisation flips the cross product.
  const Vec3 n = std::cos(v) * radial(frame_, u) + std::sin(v) * frame_.z;
  return std::cos(v) < 0.0 ? Vec3(-n) : n;
}

Vec2 SphereSurface::closest_parameters(const Vec3& p) const {
  const Cylindrical c = cylindrical(frame_, p);
  return {c.angle, std::atan2(c.height, c.rho)};
}

BoundingBox SphereSurface::bounds(const ParamBox& box) const {
  const double r = radius_;
  return detail::rotational_patch_bounds(frame_, box,
                                         [r](double alpha, double beta, double v0, double v1) {
                                           return detail::trig_range(r * alpha, r * beta, v0, v1);
                                         });
}

SurfacePtr SphereSurface::transformed(const Location& loc) const {
  return std::make_shared<SphereSurface>(frame_.transformed(loc), radius_ * loc.scale());
}

// ---- TorusSurface -------------------------------------------------------------------------

Vec3 TorusSurface::point(double u, double v) const {
  return frame_.origin + (major_ + minor_ * std::cos(v)) * radial(frame_, u) +
         minor_ * std::sin(v) * frame_.z;
}
Vec3 TorusSurface::du(double u, double v) const {
  return (major_ + minor_ * std::cos(v)) * radial_derivative(frame_, u);
}
Vec3 TorusSurface::dv(double u, double v) const {
  return minor_ * (-std::sin(v) * radial(frame_, u) + std::cos(v) * frame_.z);
}
double TorusSurface::u_period() const { return detail::kTwoPi; }
double TorusSurface::v_period() const { return detail::kTwoPi; }

Vec2 TorusSurface::closest_parameters(const Vec3& p) const {
  // R > r keeps the whole torus at ρ > 0, so the nearest point is in p's half-plane, on the
  // tube circle there: straight away from the tube centre (v = 0 on the core circle).
  const Cylindrical c = cylindrical(frame_, p);
  const double x = c.rho - major_;
  const double v =
      (x == 0.0 && c.height == 0.0) ? 0.0 : detail::wrap_two_pi(std::atan2(c.height, x));
  return {c.angle, v};
}

BoundingBox TorusSurface::bounds(const ParamBox& box) const {
  const double big = major_;
  const double small = minor_;
  return detail::rotational_patch_bounds(
      frame_, box, [big, small](double alpha, double beta, double v0, double v1) {
        const detail::ValueRange r = detail::trig_range(small * alpha, small * beta, v0, v1);
        return detail::ValueRange{alpha * big + r.min, alpha * big + r.max};
      });
}

SurfacePtr TorusSurface::transformed(const Location& loc) const {
  return std::make_shared<TorusSurface>(frame_.transformed(loc), major_ * loc.scale(),
                                        minor_ * loc.scale());
}

}  // namespace csgtile::kernel
