#include "boolean/pcurve_fit.h"

#include <Eigen/QR>
#include <cmath>
#include <numbers>
#include <vector>

namespace csgtile::kernel::detail {

namespace {

// |∂S/∂u| below this (relative to the point's distance from the origin, plus one) marks a
// point where u is undefined (a pole, an apex): it does not constrain the fit in u.
constexpr double kDegenerateDerivative = 1e-9;
// Fitted coefficients below this fraction of the largest one are rounding noise, set to zero
// so that exact curves stay exact (a line stays a line).
constexpr double kCoefficientNoise = 1e-13;

bool is_angular_curve(const Curve& c) { return c.period() > 0; }

// Affine image of a curve in a plane's (u, v) coordinates: exact for lines and trig curves.
Curve2dPtr project_on_plane(const Curve& curve, const PlaneSurface& plane) {
  const Frame& f = plane.frame();
  auto point2 = [&](const Vec3& p) {
    return Vec2((p - f.origin).dot(f.x), (p - f.origin).dot(f.y));
  };
  auto vec2 = [&](const Vec3& v) { return Vec2(v.dot(f.x), v.dot(f.y)); };
  switch (curve.kind()) {
    case CurveKind::Line: {
      const auto& l = static_cast<const LineCurve&>(curve);
      return std::make_shared<Line2d>(point2(l.origin()), vec2(l.direction()));
    }
    case CurveKind::Circle: {
      const auto& c = static_cast<const CircleCurve&>(curve);
      const Frame& cf = c.frame();
      return std::make_shared<Trig2d>(point2(cf.origin), vec2(c.radius() * cf.x),
                                      vec2(c.radius() * cf.y), Vec2::Zero());
    }
    case CurveKind::Ellipse: {
      const auto& e = static_cast<const EllipseCurve&>(curve);
      const Frame& ef = e.frame();
      return std::make_shared<Trig2d>(point2(ef.origin), vec2(e.major_radius() * ef.x),
                                      vec2(e.minor_radius() * ef.y), Vec2::Zero());
    }
    case CurveKind::Trig: {
      const auto& t = static_cast<const TrigCurve&>(curve);
      return std::make_shared<Trig2d>(point2(t.center()), vec2(t.a()), vec2(t.b()), Vec2::Zero());
    }
    case CurveKind::Polyline: {
      const auto& p = static_cast<const PolylineCurve&>(curve);
      std::vector<Vec2> pts;
      for (const Vec3& q : p.points()) pts.push_back(point2(q));
      return std::make_shared<Polyline2d>(std::move(pts));
    }
  }
  return nullptr;
}

}  // namespace

double nearest_periodic(double value, double reference, double period) {
  if (period <= 0) return value;
  return value + period * std::round((reference - value) / period);
}

double pcurve_deviation(const Curve& curve, const Curve2d& pcurve, double t0, double t1,
                        const Surface& surface, int samples) {
  double worst = 0.0;
  for (int i = 0; i < samples; ++i) {
    const double t = t0 + (t1 - t0) * i / (samples - 1);
    const Vec2 uv = pcurve.point(t);
    worst = std::max(worst, (surface.point(uv.x(), uv.y()) - curve.point(t)).norm());
  }
  return worst;
}

Curve2dPtr shift_pcurve(const Curve2dPtr& pcurve, const Vec2& offset) {
  if (offset.isZero(0.0)) return pcurve;
  switch (pcurve->kind()) {
    case Curve2dKind::Line: {
      const auto& l = static_cast<const Line2d&>(*pcurve);
      return std::make_shared<Line2d>(l.origin() + offset, l.direction());
    }
    case Curve2dKind::Circle: {
      const auto& c = static_cast<const Circle2d&>(*pcurve);
      return std::make_shared<Circle2d>(c.center() + offset, c.radius(), c.sense());
    }
    case Curve2dKind::Polyline: {
      std::vector<Vec2> pts = static_cast<const Polyline2d&>(*pcurve).points();
      for (Vec2& p : pts) p += offset;
      return std::make_shared<Polyline2d>(std::move(pts));
    }
    case Curve2dKind::Trig:
      return std::make_shared<Trig2d>(static_cast<const Trig2d&>(*pcurve).shifted(offset));
  }
  return pcurve;
}

Curve2dPtr fit_pcurve(const Curve& curve, double t0, double t1, const Surface& surface,
                      double tolerance) {
  Curve2dPtr result;
  if (surface.kind() == SurfaceKind::Plane) {
    result = project_on_plane(curve, static_cast<const PlaneSurface&>(surface));
  } else {
    // Inverted samples; points where u is undefined (poles, apex) do not constrain u.
    constexpr int kSamples = 24;
    const bool angular = is_angular_curve(curve);
    const int basis = angular ? 4 : 2;
    std::vector<double> ts;
    std::vector<Vec2> uvs;
    std::vector<bool> u_defined;
    for (int i = 0; i < kSamples; ++i) {
      const double t = t0 + (t1 - t0) * (i + 0.5) / kSamples;
      const Vec3 p = curve.point(t);
      Vec2 uv = surface.closest_parameters(p);
      const double du = surface.du(uv.x(), uv.y()).norm();
      ts.push_back(t);
      uvs.push_back(uv);
      u_defined.push_back(du > kDegenerateDerivative * (1.0 + p.norm()));
    }
    // Unwrap periodic parameters along the curve.
    for (std::size_t i = 1; i < uvs.size(); ++i) {
      if (u_defined[i]) {
        std::size_t j = i;
        while (j > 0 && !u_defined[j - 1]) --j;
        if (j > 0) uvs[i].x() = nearest_periodic(uvs[i].x(), uvs[j - 1].x(), surface.u_period());
      }
      uvs[i].y() = nearest_periodic(uvs[i].y(), uvs[i - 1].y(), surface.v_period());
    }
    auto fit = [&](int coordinate) -> Eigen::Vector4d {
      std::vector<int> rows;
      for (int i = 0; i < kSamples; ++i) {
        if (coordinate == 1 || u_defined[static_cast<std::size_t>(i)]) rows.push_back(i);
      }
      Eigen::MatrixXd m(static_cast<int>(rows.size()), basis);
      Eigen::VectorXd rhs(static_cast<int>(rows.size()));
      for (int r = 0; r < static_cast<int>(rows.size()); ++r) {
        const auto i = static_cast<std::size_t>(rows[static_cast<std::size_t>(r)]);
        const double t = ts[i];
        if (angular) {
          m.row(r) << 1.0, std::cos(t), std::sin(t), t;
        } else {
          m.row(r) << 1.0, t;
        }
        rhs(r) = coordinate == 0 ? uvs[i].x() : uvs[i].y();
      }
      Eigen::VectorXd x = m.colPivHouseholderQr().solve(rhs);
      Eigen::Vector4d out = Eigen::Vector4d::Zero();
      if (angular) {
        out = x;
      } else {
        out(0) = x(0);
        out(3) = x(1);
      }
      // Clean coefficients that are rounding noise so that exact curves stay exact.
      const double scale = std::max(1.0, out.cwiseAbs().maxCoeff());
      for (int k = 0; k < 4; ++k) {
        if (std::abs(out(k)) < kCoefficientNoise * scale) out(k) = 0.0;
      }
      return out;
    };
    const Eigen::Vector4d fu = fit(0), fv = fit(1);
    if (fu(1) == 0.0 && fu(2) == 0.0 && fv(1) == 0.0 && fv(2) == 0.0) {
      // No trigonometric part: c + t·d is a line of the parameter plane (a ruling of a
      // cylinder, a circle along a cylinder's u), the same points, sampled as a line.
      result = std::make_shared<Line2d>(Vec2(fu(0), fv(0)), Vec2(fu(3), fv(3)));
    } else {
      result = std::make_shared<Trig2d>(Vec2(fu(0), fv(0)), Vec2(fu(1), fv(1)), Vec2(fu(2), fv(2)),
                                        Vec2(fu(3), fv(3)));
    }
  }
  if (!result) return nullptr;
  // A line's projection on a plane differs from it only along the normal, by an affine
  // function of t: its two ends bound the deviation (most section edges of polyhedral input).
  const bool affine = surface.kind() == SurfaceKind::Plane && curve.kind() == CurveKind::Line;
  if (pcurve_deviation(curve, *result, t0, t1, surface, affine ? 2 : 97) > tolerance) {
    return nullptr;
  }
  return result;
}

}  // namespace csgtile::kernel::detail
