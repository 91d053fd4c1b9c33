#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <utility>

#include "csgtile/kernel/surface.h"
#include "geometry/geometry_internal.h"

namespace csgtile::kernel {

namespace {

/// v minus its component along the unit vector d.
Vec3 flatten(const Vec3& v, const Vec3& d) { return v - v.dot(d) * d; }

/// Parameter of the point of the conic O + A·cos t + B·sin t closest to q, all projected
/// along the unit vector d. The projection of a circle or ellipse is an ellipse given by
/// conjugate semi-diameters A⊥, B⊥; rotating the parameter by θ turns them into principal
/// semi-axes, where the planar ellipse solver applies. Result in [0, 2π).
double projected_conic_closest(const Vec3& origin, const Vec3& a, const Vec3& b, const Vec3& q,
                               const Vec3& d) {
  const Vec3 fa = flatten(a, d);
  const Vec3 fb = flatten(b, d);
  // |A⊥ cos t + B⊥ sin t|² is extremal where tan 2t = 2 A⊥·B⊥ / (|A⊥|² − |B⊥|²).
  const double theta = 0.5 * std::atan2(2.0 * fa.dot(fb), fa.squaredNorm() - fb.squaredNorm());
  const Vec3 major = std::cos(theta) * fa + std::sin(theta) * fb;
  const Vec3 minor = -std::sin(theta) * fa + std::cos(theta) * fb;
  const double major_length = major.norm();
  const double minor_length = minor.norm();
  const Vec3 p = flatten(q - origin, d);
  const double x = major_length > 0.0 ? p.dot(major) / major_length : 0.0;
  const double y = minor_length > 0.0 ? p.dot(minor) / minor_length : 0.0;
  const double tau = detail::ellipse_closest_angle(major_length, minor_length, x, y, -theta,
                                                   detail::kTwoPi - theta);
  return detail::wrap_two_pi(tau + theta);
}

/// Parameter of the point of the basis curve closest to p after projecting both along the
/// unit vector d (the extrusion direction).
double projected_closest_parameter(const Curve& curve, const Vec3& p, const Vec3& d) {
  switch (curve.kind()) {
    case CurveKind::Line: {
      const auto& line = static_cast<const LineCurve&>(curve);
      const Vec3 fd = flatten(line.direction(), d);
      const double dd = fd.squaredNorm();
      // A line parallel to d sweeps a degenerate surface where every u is as good.
      if (dd <= 1e-24) return 0.0;
      return flatten(p - line.origin(), d).dot(fd) / dd;
    }
    case CurveKind::Circle: {
      const auto& circle = static_cast<const CircleCurve&>(curve);
      const Frame& f = circle.frame();
      return projected_conic_closest(f.origin, circle.radius() * f.x, circle.radius() * f.y, p, d);
    }
    case CurveKind::Ellipse: {
      const auto& ellipse = static_cast<const EllipseCurve&>(curve);
      const Frame& f = ellipse.frame();
      return projected_conic_closest(f.origin, ellipse.major_radius() * f.x,
                                     ellipse.minor_radius() * f.y, p, d);
    }
    case CurveKind::Trig: {
      const auto& trig = static_cast<const TrigCurve&>(curve);
      return projected_conic_closest(trig.center(), trig.a(), trig.b(), p, d);
    }
    case CurveKind::Polyline: {
      const auto& points = static_cast<const PolylineCurve&>(curve).points();
      double best_t = 0.0;
      double best_d2 = std::numeric_limits<double>::infinity();
      for (std::size_t i = 0; i + 1 < points.size(); ++i) {
        const Vec3 a = flatten(points[i] - p, d);
        const Vec3 s = flatten(points[i + 1] - points[i], d);
        const double ss = s.squaredNorm();
        const double f = ss > 0.0 ? std::clamp(-a.dot(s) / ss, 0.0, 1.0) : 0.0;
        const double d2 = (a + f * s).squaredNorm();
        // Strict comparison in ascending t: ties keep the smallest parameter.
        if (d2 < best_d2) {
          best_d2 = d2;
          best_t = static_cast<double>(i) + f;
        }
      }
      return best_t;
    }
  }
  return 0.0;
}

/// Unit vector ⊥ axis in the meridian's plane, pointing to the meridian's side: the side of
/// a reference point (line origin, conic centre, farthest polyline vertex), falling back to
/// further points when that one is on the axis. Any choice works for evaluation and bounds
/// (the radial coordinate is signed); it only decides the normal's side exactly on the axis.
Vec3 meridian_radial_direction(const Curve& meridian, const Vec3& axis_origin, const Vec3& axis) {
  std::array<Vec3, 3> references{};
  std::size_t count = 0;
  Vec3 exact_direction = Vec3::Zero();
  switch (meridian.kind()) {
    case CurveKind::Line: {
      const auto& line = static_cast<const LineCurve&>(meridian);
      references[count++] = line.origin() - axis_origin;
      references[count++] = line.origin() + line.direction() - axis_origin;
      break;
    }
    case CurveKind::Circle:
    case CurveKind::Ellipse: {
      const Frame& f = meridian.kind() == CurveKind::Circle
                           ? static_cast<const CircleCurve&>(meridian).frame()
                           : static_cast<const EllipseCurve&>(meridian).frame();
      // The conic's plane contains the axis, so axis × plane normal is exactly radial.
      exact_direction = axis.cross(f.z);
      references[count++] = f.origin - axis_origin;
      references[count++] = meridian.point(0.0) - axis_origin;
      references[count++] = meridian.point(0.5 * detail::kPi) - axis_origin;
      break;
    }
    case CurveKind::Trig: {
      const auto& trig = static_cast<const TrigCurve&>(meridian);
      exact_direction = axis.cross(trig.a().cross(trig.b()).normalized());
      references[count++] = trig.center() - axis_origin;
      references[count++] = meridian.point(0.0) - axis_origin;
      references[count++] = meridian.point(0.5 * detail::kPi) - axis_origin;
      break;
    }
    case CurveKind::Polyline: {
      const auto& points = static_cast<const PolylineCurve&>(meridian).points();
      Vec3 farthest = Vec3::Zero();
      for (const Vec3& p : points) {
        const Vec3 r = p - axis_origin;
        if (flatten(r, axis).squaredNorm() > flatten(farthest, axis).squaredNorm()) farthest = r;
      }
      references[count++] = farthest;
      break;
    }
  }
  double scale = 0.0;
  for (std::size_t i = 0; i < count; ++i) scale = std::max(scale, references[i].norm());
  Vec3 side = Vec3::Zero();
  for (std::size_t i = 0; i < count; ++i) {
    const Vec3 r = flatten(references[i], axis);
    if (r.norm() > 1e-12 * scale) {
      side = r;
      break;
    }
  }
  Vec3 direction = side;
  if (exact_direction.norm() > 0.5) {
    direction = exact_direction.dot(side) < 0.0 ? Vec3(-exact_direction) : exact_direction;
  }
  const double n = direction.norm();
  return n > 0.0 ? Vec3(direction / n) : detail::any_perpendicular(axis);
}

}  // namespace

// ---- ExtrusionSurface ---------------------------------------------------------------------

ExtrusionSurface::ExtrusionSurface(CurvePtr basis, const Vec3& direction)
    : basis_(std::move(basis)), direction_(direction.normalized()) {}

Vec3 ExtrusionSurface::point(double u, double v) const { return basis_->point(u) + v * direction_; }
Vec3 ExtrusionSurface::du(double u, double) const { return basis_->derivative(u); }
Vec3 ExtrusionSurface::dv(double, double) const { return direction_; }

Vec2 ExtrusionSurface::closest_parameters(const Vec3& p) const {
  // For fixed u the best v is the projection on D; what remains is the distance between p
  // and the basis after both are projected along D.
  const double u = projected_closest_parameter(*basis_, p, direction_);
  return {u, (p - basis_->point(u)).dot(direction_)};
}

BoundingBox ExtrusionSurface::bounds(const ParamBox& box) const {
  // S·e = C(u)·e + v·D·e separates: the basis support plus the extreme of the linear term.
  BoundingBox out;
  for (int i = 0; i < 3; ++i) {
    const Vec3 axis = Vec3::Unit(i);
    const detail::ValueRange rv = detail::linear_range(direction_[i], 0.0, box.v0, box.v1);
    out.max[i] = basis_->support(axis, box.u0, box.u1) + rv.max;
    out.min[i] = -basis_->support(-axis, box.u0, box.u1) + rv.min;
  }
  return out;
}

SurfacePtr ExtrusionSurface::transformed(const Location& loc) const {
  // v is a length along the unit direction and scales; u follows the basis curve's rule.
  return std::make_shared<ExtrusionSurface>(basis_->transformed(loc),
                                            loc.apply_direction(direction_));
}

// ---- RevolutionSurface --------------------------------------------------------------------

RevolutionSurface::RevolutionSurface(CurvePtr meridian, const Vec3& axis_origin,
                                     const Vec3& axis_direction)
    : meridian_(std::move(meridian)),
      origin_(axis_origin),
      direction_(axis_direction.normalized()),
      radial_(meridian_radial_direction(*meridian_, origin_, direction_)) {}

Vec3 RevolutionSurface::point(double u, double v) const {
  // Rodrigues: rotation of V = C(v) − P by u about D.
  const Vec3 w = meridian_->point(v) - origin_;
  const Vec3 along = w.dot(direction_) * direction_;
  return origin_ + along + std::cos(u) * (w - along) + std::sin(u) * direction_.cross(w);
}

Vec3 RevolutionSurface::du(double u, double v) const {
  const Vec3 w = meridian_->point(v) - origin_;
  const Vec3 along = w.dot(direction_) * direction_;
  return -std::sin(u) * (w - along) + std::cos(u) * direction_.cross(w);
}

Vec3 RevolutionSurface::dv(double u, double v) const {
  const Vec3 w = meridian_->derivative(v);
  const Vec3 along = w.dot(direction_) * direction_;
  return along + std::cos(u) * (w - along) + std::sin(u) * direction_.cross(w);
}

double RevolutionSurface::u_period() const { return detail::kTwoPi; }

Vec3 RevolutionSurface::normal(double u, double v) const {
  // With V = z·D + ρ·X (X = radial_, ρ signed) and C' in the meridian plane,
  // du × dv = ρ·R_u(C'·D·X − C'·X·D): dividing out ρ gives the limit on the axis too.
  const Vec3 c1 = meridian_->derivative(v);
  const Vec3 e = std::cos(u) * radial_ + std::sin(u) * direction_.cross(radial_);
  const Vec3 n = c1.dot(direction_) * e - c1.dot(radial_) * direction_;
  const double len = n.norm();
  if (!(len > 0.0)) return Surface::normal(u, v);
  const double rho = (meridian_->point(v) - origin_).dot(radial_);
  return rho < 0.0 ? Vec3(-n / len) : Vec3(n / len);
}

Vec2 RevolutionSurface::closest_parameters(const Vec3& p) const {
  // Rotating p about the axis into the meridian's plane, on either side of the axis, and
  // inverting on the meridian there covers every surface point: a meridian point at signed
  // radius ρ is nearest to p's circle of latitude on the side of sign(ρ).
  const Vec3 q = p - origin_;
  const double z = q.dot(direction_);
  const Vec3 w = q - z * direction_;
  const double rho = w.norm();
  const double angle =
      rho > 0.0 ? std::atan2(w.dot(direction_.cross(radial_)), w.dot(radial_)) : 0.0;
  const double t0 = meridian_->first_parameter();
  const double t1 = meridian_->last_parameter();
  const auto invert_on_side = [&](double side) {
    const Vec3 in_plane = origin_ + z * direction_ + side * rho * radial_;
    const double v = meridian_->closest_parameter(in_plane, t0, t1);
    return Vec2(detail::wrap_two_pi(side > 0.0 ? angle : angle + detail::kPi), v);
  };
  Vec2 same = invert_on_side(1.0);
  if (rho == 0.0) return same;  // both sides are the same point
  const Vec2 mirrored = invert_on_side(-1.0);
  const Vec3 s_same = point(same.x(), same.y());
  // The mirrored side must win by more than rounding: a meridian crossing the axis covers
  // points twice, and the meridian's own side (radial_) is then the expected answer.
  const double noise = 1e-13 * (q.norm() + (s_same - origin_).norm());
  const double d_same = (s_same - p).squaredNorm();
  const double d_mirrored = (point(mirrored.x(), mirrored.y()) - p).squaredNorm();
  return d_mirrored < d_same - noise * noise ? mirrored : same;
}

BoundingBox RevolutionSurface::bounds(const ParamBox& box) const {
  // S = P + ρ(v)·(cos u·X + sin u·Y) + z(v)·D with (ρ, z) the meridian's coordinates; for a
  // fixed u, α·ρ(v) + β·z(v) = (C(v) − P)·(α·X + β·D), whose range is exact from the
  // meridian's support function.
  Frame f;
  f.origin = origin_;
  f.x = radial_;
  f.y = direction_.cross(radial_);
  f.z = direction_;
  const Curve& meridian = *meridian_;
  const Vec3 origin = origin_;
  return detail::rotational_patch_bounds(
      f, box, [&](double alpha, double beta, double v0, double v1) {
        const Vec3 w = alpha * f.x + beta * f.z;
        const double shift = origin.dot(w);
        return detail::ValueRange{-meridian.support(-w, v0, v1) - shift,
                                  meridian.support(w, v0, v1) - shift};
      });
}

SurfacePtr RevolutionSurface::transformed(const Location& loc) const {
  // u is an angle and is kept; v follows the meridian's rule (a line's t scales).
  return std::make_shared<RevolutionSurface>(meridian_->transformed(loc), loc.apply_point(origin_),
                                             loc.apply_direction(direction_));
}

}  // namespace csgtile::kernel
