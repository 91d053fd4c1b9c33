// Plane geometry of the fitting module (plane2d.h). The proposers' outputs depend on these
// to the last bit: keep the order of every sum and comparison when changing them.

#include "plane2d.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Cholesky>

namespace csgtile::fit::detail {

std::vector<Vec2> convex_hull(std::vector<Vec2> points) {
  std::sort(points.begin(), points.end(), [](const Vec2& a, const Vec2& b) {
    return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
  });
  points.erase(std::unique(points.begin(), points.end()), points.end());
  if (points.size() < 3) return points;
  std::vector<Vec2> hull(2 * points.size());
  std::size_t k = 0;
  for (const auto& p : points) {
    while (k >= 2 && cross2(hull[k - 2], hull[k - 1], p) <= 0) --k;
    hull[k++] = p;
  }
  for (std::size_t i = points.size() - 1, t = k + 1; i-- > 0;) {
    while (k >= t && cross2(hull[k - 2], hull[k - 1], points[i]) <= 0) --k;
    hull[k++] = points[i];
  }
  hull.resize(k - 1);
  return hull;
}

std::vector<Vec2> OrientedRectangle::corners() const {
  const Vec2 perp = across();
  return {a0 * dir + b0 * perp, a1 * dir + b0 * perp, a1 * dir + b1 * perp, a0 * dir + b1 * perp};
}

std::optional<OrientedRectangle> smallest_rectangle(const std::vector<Vec2>& polygon,
                                                    double slack) {
  double best = INFINITY;
  std::optional<OrientedRectangle> out;
  for (std::size_t k = 0; k < polygon.size(); ++k) {
    Vec2 dir = polygon[(k + 1) % polygon.size()] - polygon[k];
    if (dir.norm() <= 0.0) continue;
    dir.normalize();
    const Vec2 perp(-dir.y(), dir.x());
    double a0 = INFINITY, a1 = -INFINITY, b0 = INFINITY, b1 = -INFINITY;
    for (const auto& p : polygon) {
      a0 = std::min(a0, p.dot(dir));
      a1 = std::max(a1, p.dot(dir));
      b0 = std::min(b0, p.dot(perp));
      b1 = std::max(b1, p.dot(perp));
    }
    const double area = (a1 - a0) * (b1 - b0);
    if (area < best - slack) {
      best = area;
      out = OrientedRectangle{dir, a0, a1, b0, b1};
    }
  }
  return out;
}

Eigen::Matrix3d frame_of(const Vec3& x, const Vec3& z) {
  Eigen::Matrix3d r;
  r.col(2) = z.normalized();
  r.col(1) = r.col(2).cross(x).normalized();
  r.col(0) = r.col(1).cross(r.col(2)).normalized();
  return r;
}

std::optional<kernel::Location> place(const Eigen::Matrix3d& rotation, const Vec3& origin) {
  kernel::Matrix34 q;
  q.leftCols<3>() = rotation;
  q.col(3) = origin;
  auto loc = kernel::Location::from_matrix(q);
  if (!loc.ok()) return std::nullopt;
  return loc.value();
}

std::optional<Circle2> fit_circle(const std::vector<Vec2>& points) {
  Eigen::Matrix3d normal_matrix = Eigen::Matrix3d::Zero();
  Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
  for (const Vec2& q : points) {
    const Eigen::Vector3d row(q.x(), q.y(), 1.0);
    normal_matrix += row * row.transpose();
    rhs -= row * q.squaredNorm();
  }
  const Eigen::Vector3d abc = normal_matrix.ldlt().solve(rhs);
  const Vec2 centre(-0.5 * abc.x(), -0.5 * abc.y());
  const double r2 = centre.squaredNorm() - abc.z();
  if (!(r2 > 0.0) || !std::isfinite(r2)) return std::nullopt;
  return Circle2{centre, std::sqrt(r2)};
}

std::optional<PrincipalFrame> principal_frame(const std::vector<Vec2>& points) {
  const auto hull = convex_hull(points);
  if (hull.size() < 3) return std::nullopt;
  const auto rectangle = smallest_rectangle(hull, 1e-9);
  PrincipalFrame f;
  f.u = rectangle ? rectangle->dir : Vec2(1, 0);
  f.v = Vec2(-f.u.y(), f.u.x());
  f.a0 = f.b0 = INFINITY;
  f.a1 = f.b1 = -INFINITY;
  for (const auto& p : points) {
    f.a0 = std::min(f.a0, p.dot(f.u));
    f.a1 = std::max(f.a1, p.dot(f.u));
    f.b0 = std::min(f.b0, p.dot(f.v));
    f.b1 = std::max(f.b1, p.dot(f.v));
  }
  return f;
}

}  // namespace csgtile::fit::detail
