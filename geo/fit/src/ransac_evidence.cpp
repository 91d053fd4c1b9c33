// Type selection by evidence (RansacOptions::by_evidence) and simpler surfaces: which type of
// surface a detected shape's points are, compared on the same points by an information
// criterion, and on exact clouds the surface that fits its own points exactly (exact_core).

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include <Eigen/Dense>

#include "plane2d.h"
#include "ransac_detector.h"

namespace csgtile::fit::detail {

// Bayesian information criterion of a surface on points: n·ln(RSS/n) + k·ln(n), k its
// parameter count, the residual floored at the noise (or a twentieth of epsilon on exact
// points), so that on noisy points the simpler surface wins at equal error and on exact ones
// the surface whose error is clearly smaller does.
double Detector::criterion(const Surface& s, std::span<const std::uint32_t> inliers) const {
  const double n = static_cast<double>(std::max<std::size_t>(inliers.size(), 1));
  double rss = 0.0;
  for (auto i : inliers) {
    const double d = surface_distance(s, points_[i]);
    rss += d * d;
  }
  return detail::information_criterion(rss, n, noise_floor(), detail::parameter_count(s.type), n);
}

// A cylinder through points with normals: its axis is the direction the normals avoid (the
// least principal direction of their scatter), its circle the least-squares one of the points
// projected across the axis; refined by least squares. nullopt for too few normals.
std::optional<Surface> Detector::cylinder_from_normals(
    std::span<const std::uint32_t> inliers) const {
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  std::size_t count = 0;
  for (auto i : inliers) {
    if (!has_normal_[i]) continue;
    scatter += normals_[i] * normals_[i].transpose();
    ++count;
  }
  if (count < 5) return std::nullopt;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(scatter);
  if (eig.info() != Eigen::Success) return std::nullopt;
  const auto s = circle_along(eig.eigenvectors().col(0).normalized(), inliers);
  if (!s) return std::nullopt;
  return detail::refine_surface(*s, points_, inliers);
}

// The cylinder along `axis` through the least-squares circle of the points seen along it (not
// refined); nullopt when no circle fits or its radius reaches max_radius.
std::optional<Surface> Detector::circle_along(const Vec3& axis,
                                              std::span<const std::uint32_t> inliers) const {
  if (inliers.empty()) return std::nullopt;
  Vec3 e1, e2;
  detail::orthonormal_basis(axis, e1, e2);
  const Vec3 origin = points_[inliers[0]];
  std::vector<kernel::Vec2> across;
  across.reserve(inliers.size());
  for (auto i : inliers) {
    const Vec3 d = points_[i] - origin;
    across.emplace_back(d.dot(e1), d.dot(e2));
  }
  const auto circle = detail::fit_circle(across);
  if (!circle || !(circle->radius < o_.max_radius)) return std::nullopt;
  Surface s;
  s.type = ShapeType::Cylinder;
  s.axis = detail::canonical_axis(axis);
  s.point = origin + circle->centre.x() * e1 + circle->centre.y() * e2;
  s.radius = circle->radius;
  return s;
}

// A cylinder through the points of a plane that bend away from it: their heights over the
// plane as a quadratic h(u, v); the direction it curves most along is across the axis, its
// curvature 1/r. Refined by least squares; nullopt when the points do not curve.
std::optional<Surface> Detector::cylinder_across_plane(
    const Surface& plane, std::span<const std::uint32_t> inliers) const {
  if (inliers.size() < 8) return std::nullopt;
  Vec3 e1, e2;
  detail::orthonormal_basis(plane.axis, e1, e2);
  const Vec3 centre = centroid_of(inliers);
  Eigen::MatrixXd a(inliers.size(), 6);
  Eigen::VectorXd h(inliers.size());
  for (std::size_t k = 0; k < inliers.size(); ++k) {
    const Vec3 d = points_[inliers[k]] - centre;
    const double u = d.dot(e1), v = d.dot(e2);
    a.row(static_cast<Eigen::Index>(k)) << u * u, u * v, v * v, u, v, 1.0;
    h(static_cast<Eigen::Index>(k)) = d.dot(plane.axis);
  }
  const Eigen::VectorXd c = a.colPivHouseholderQr().solve(h);
  if (!c.allFinite()) return std::nullopt;
  Eigen::Matrix2d hessian;
  hessian << 2.0 * c(0), c(1), c(1), 2.0 * c(2);
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(hessian);
  if (eig.info() != Eigen::Success) return std::nullopt;
  const int most = std::abs(eig.eigenvalues()(0)) > std::abs(eig.eigenvalues()(1)) ? 0 : 1;
  const double k = eig.eigenvalues()(most);
  if (!(std::abs(k) > 0.0) || !std::isfinite(k)) return std::nullopt;
  const Eigen::Vector2d along = eig.eigenvectors().col(1 - most);
  Surface s;
  s.type = ShapeType::Cylinder;
  s.radius = 1.0 / std::abs(k);
  if (!(s.radius < o_.max_radius)) return std::nullopt;
  s.axis = detail::canonical_axis((along.x() * e1 + along.y() * e2).normalized());
  // The centre of curvature lies on the side the points bend towards.
  s.point = centre + (k > 0.0 ? 1.0 : -1.0) * s.radius * plane.axis;
  return detail::refine_surface(s, points_, inliers);
}

// The cylinder along `axis` through the points' circle when they lie on it (every point within
// the noise floor of it on the whole), else nullopt.
std::optional<Surface> Detector::on_one_circle(const Vec3& axis,
                                               std::span<const std::uint32_t> inliers) const {
  auto circle = circle_along(axis, inliers);
  if (!circle || !(rms_of(*circle, inliers) <= noise_floor())) return std::nullopt;
  return circle;
}

// A plane whose points lie on one circle of it is the ring where a cylinder's wall (a hole, a
// pin) meets the plane: when points of other shapes or none lie on that cylinder next to the
// ring but off its plane (the wall's rims and rows), the cylinder.
std::optional<Surface> Detector::wall_through_ring(const Surface& plane,
                                                   std::span<const std::uint32_t> inliers) {
  if (inliers.size() < 6) return std::nullopt;
  auto wall = on_one_circle(plane.axis, inliers);
  if (!wall) return std::nullopt;
  std::size_t off = 0;
  for_points_near(inliers, [&](std::uint32_t j) {
    if (std::abs(surface_distance(*wall, points_[j])) <= o_.epsilon &&
        std::abs(surface_distance(plane, points_[j])) > o_.epsilon) {
      ++off;
    }
  });
  if (2 * off < inliers.size()) return std::nullopt;
  // The ring's normals are those of the plane it was taken for (a sparse wall's points find
  // their neighbours on the ring): no evidence against the wall.
  for (auto i : inliers) has_normal_[i] = 0;
  return wall;
}

// A cone through points with normals: turned towards `inside` (a point on the cone's concave
// side, e.g. the centre of a sphere fitted to the same points), a cone's normals all make the
// angle 90° − θ with its axis, so their tips lie on one plane whose normal is the axis (the
// least principal direction of their centred scatter) at distance sin θ from the origin; the
// apex is the point every tangent plane passes through (least squares). Refined by least
// squares; nullopt for too few normals, a cylinder (θ under a degree) or a singular apex.
std::optional<Surface> Detector::cone_from_normals(std::span<const std::uint32_t> inliers,
                                                   const Vec3& inside) const {
  std::vector<Vec3> in;
  std::vector<std::uint32_t> used;
  for (auto i : inliers) {
    if (!has_normal_[i]) continue;
    in.push_back(normals_[i].dot(inside - points_[i]) < 0.0 ? Vec3(-normals_[i]) : normals_[i]);
    used.push_back(i);
  }
  if (in.size() < 6) return std::nullopt;
  Vec3 mean = Vec3::Zero();
  for (const Vec3& n : in) mean += n;
  mean /= static_cast<double>(in.size());
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (const Vec3& n : in) scatter += (n - mean) * (n - mean).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(scatter);
  if (eig.info() != Eigen::Success) return std::nullopt;
  Vec3 axis = eig.eigenvectors().col(0).normalized();
  double sin_angle = mean.dot(axis);
  if (sin_angle < 0.0) {
    axis = -axis;
    sin_angle = -sin_angle;
  }
  if (!(sin_angle > std::sin(std::numbers::pi / 180.0)) || !(sin_angle < 1.0)) return std::nullopt;
  Eigen::Matrix3d a = Eigen::Matrix3d::Zero();
  Vec3 b = Vec3::Zero();
  for (std::size_t k = 0; k < in.size(); ++k) {
    const Eigen::Matrix3d nn = in[k] * in[k].transpose();
    a += nn;
    b += nn * points_[used[k]];
  }
  const Eigen::FullPivLU<Eigen::Matrix3d> lu(a);
  if (!lu.isInvertible()) return std::nullopt;
  Surface s;
  s.type = ShapeType::Cone;
  s.point = lu.solve(b);
  s.axis = axis;
  s.angle = std::asin(sin_angle);
  if (!s.point.allFinite()) return std::nullopt;
  return detail::refine_surface(s, points_, inliers);
}

// Type selection by evidence: the plane and the cylinder (for a sphere also the cone) that fit
// the same points are compared by the criterion above; another type replaces the shape when
// it keeps nearly all of its points and scores clearly better, or, where the errors lie below
// the criterion's floor, when its error is a small share of the shape's (a tenth; a hundredth
// for a plane within the floor). A plane is only questioned on exact clouds: a ring of a hole's
// wall, a strip of a wide cylinder.
std::optional<Surface> Detector::by_evidence(const Surface& s,
                                             std::span<const std::uint32_t> inliers) {
  if (s.type == ShapeType::Plane) {
    // A plane stays a plane unless its points stray from it by more than a quarter of the floor
    // and a cylinder through them is exact, within the floor and within a tenth of the plane's
    // error (a narrow strip of a wide cylinder, the root of a gear between two teeth, bends by
    // less than the floor; what marks it is the cylinder's far smaller error): on exact clouds
    // only, since on noisy ones the edge points it took from its neighbours would bend a
    // cylinder towards them (and a bent plane is never exact).
    if (!exact_) return std::nullopt;
    if (auto wall = wall_through_ring(s, inliers)) return wall;
    const double floor = noise_floor();
    const double flat = rms_of(s, inliers);
    if (!(flat > 0.25 * floor)) return std::nullopt;
    auto cylinder = cylinder_across_plane(s, inliers);
    if (!cylinder || !keeps_most(*cylinder, inliers)) return std::nullopt;
    const double bent = rms_of(*cylinder, inliers);
    if (!(bent <= std::min(floor, 0.1 * flat))) return std::nullopt;
    // A cylinder fitting the points a hundred times better is the surface they lie on. Within
    // the floor nothing else counts: the criterion sees no difference there. Just above it,
    // on few points, the criterion's penalty for two more parameters outweighs the error it
    // sees (a fillet strip sampled in three columns, bending by 1.02 floors over ten points).
    if (bent <= 0.01 * flat) return cylinder;
    if (flat <= floor) return std::nullopt;
    if (criterion(*cylinder, inliers) < criterion(s, inliers) - evidence_margin(inliers)) {
      return cylinder;
    }
    return std::nullopt;
  }
  std::vector<Surface> options;
  if (auto plane = detail::fit_plane(points_, inliers)) options.push_back(*plane);
  if (s.type != ShapeType::Cylinder && o_.shapes[static_cast<int>(ShapeType::Cylinder)]) {
    if (auto cylinder = cylinder_from_normals(inliers)) options.push_back(*cylinder);
  }
  if (s.type == ShapeType::Sphere && o_.shapes[static_cast<int>(ShapeType::Cone)]) {
    // A wide cone's belt is nearly a sphere's: its normals tell them apart.
    if (auto cone = cone_from_normals(inliers, s.point)) options.push_back(*cone);
  }
  std::erase_if(options, [&](const Surface& alt) { return !keeps_most(alt, inliers); });
  double best = criterion(s, inliers) - evidence_margin(inliers);
  std::optional<Surface> chosen;
  for (const Surface& alt : options) {
    const double score = criterion(alt, inliers);
    if (score < best) {
      best = score;
      chosen = alt;
    }
  }
  if (chosen) return chosen;
  // Below the floor the criterion cannot tell errors apart, so the surface of fewer parameters
  // wins. But a surface whose points fit another to a tenth of the floor and of its own error
  // has them exact on the other (the belt of a cylinder, taken for the sphere through its
  // middle circle, fits that sphere within a cloud-wide noise estimate and the cylinder to
  // rounding): the other, the one of fewest parameters when several are.
  const double own = rms_of(s, inliers);
  const double exact = 0.1 * std::min(noise_floor(), own);
  for (const Surface& alt : options) {
    if (!(rms_of(alt, inliers) <= exact)) continue;
    if (!chosen || detail::parameter_count(alt.type) < detail::parameter_count(chosen->type)) {
      chosen = alt;
    }
  }
  return chosen;
}

std::optional<Surface> Detector::simpler(const Surface& s, std::span<const std::uint32_t> inliers) {
  // A simpler surface replaces a curved one when it keeps nearly all of its points: fewer
  // parameters at equal error (a plane patch is also a large-radius cylinder). With
  // `by_evidence`, only when it also scores no worse by the information criterion (on exact
  // points a fillet's plane keeps its points but not its error).
  const double own = o_.by_evidence ? criterion(s, inliers) : 0.0;
  auto keeps = [&](const Surface& alt) {
    if (o_.by_evidence && criterion(alt, inliers) > own) return false;
    return keeps_most(alt, inliers);
  };
  if (s.type != ShapeType::Plane) {
    if (auto plane = detail::fit_plane(points_, inliers); plane && keeps(*plane)) return plane;
  }
  if (s.type == ShapeType::Cone || s.type == ShapeType::Torus) {
    Surface cylinder;
    cylinder.type = ShapeType::Cylinder;
    cylinder.axis = s.axis;
    cylinder.point = s.point;
    double sum = 0.0;
    for (auto i : inliers)
      sum += (points_[i] - s.point - (points_[i] - s.point).dot(s.axis) * s.axis).norm();
    cylinder.radius = sum / static_cast<double>(std::max<std::size_t>(inliers.size(), 1));
    if (auto refined = detail::refine_surface(cylinder, points_, inliers);
        refined && refined->radius < o_.max_radius && keeps(*refined)) {
      return refined;
    }
  }
  if (s.type == ShapeType::Torus && !inliers.empty()) {
    // A torus whose tube is seen over a short arc of a large circle: the cylinder along the
    // tube, its axis the circle's tangent at the points' centroid.
    const Vec3 centroid = centroid_of(inliers);
    const Vec3 w = centroid - s.point - (centroid - s.point).dot(s.axis) * s.axis;
    if (w.norm() > 0.0) {
      const Vec3 u = w.normalized();
      Surface tube;
      tube.type = ShapeType::Cylinder;
      tube.axis = detail::canonical_axis(s.axis.cross(u).normalized());
      tube.point = s.point + s.radius * u;
      tube.radius = s.radius2;
      if (auto refined = detail::refine_surface(tube, points_, inliers);
          refined && refined->radius < o_.max_radius && keeps(*refined)) {
        return refined;
      }
    }
    Surface sphere;
    sphere.type = ShapeType::Sphere;
    sphere.point = s.point;
    sphere.radius = s.radius + s.radius2;
    if (auto refined = detail::refine_surface(sphere, points_, inliers);
        refined && refined->radius < o_.max_radius && keeps(*refined)) {
      return refined;
    }
  }
  return std::nullopt;
}

// On an exact cloud, a curved surface refitted to every point within epsilon of it compromises
// between its own points and those of tangent neighbours (past a fillet's tangent lines its
// plane and cylinder stay within epsilon of it for a while; a tube's rounded end is two fillets
// that one wider torus nearly fits), and fits none of them exactly. Least trimmed squares find
// the surface that fits half of the points best: refitted to the half it fits best, again
// (each step lowers that half's error), it comes to fit a surface's own points exactly when
// they are half of them or more. That surface, or nullopt when the points fit it already or no
// half becomes exact.
std::optional<Surface> Detector::exact_core(const Surface& s,
                                            std::span<const std::uint32_t> inliers) {
  if (!exact_ || s.type == ShapeType::Plane) return std::nullopt;
  const double floor = noise_floor();
  if (rms_of(s, inliers) <= floor) return std::nullopt;
  const std::size_t half = inliers.size() / 2;
  if (half < std::max(static_cast<std::size_t>(o_.min_points),
                      static_cast<std::size_t>(detail::parameter_count(s.type)) + 2)) {
    return std::nullopt;
  }
  Surface current = s;
  std::vector<std::uint32_t> core;
  for (int step = 0; step < 10; ++step) {
    best_fitting_half(current, inliers, core);
    auto refit = detail::refine_surface(current, points_, core);
    if (!refit) return std::nullopt;
    current = *refit;
    if (rms_of(current, core) <= floor) return current;
  }
  return std::nullopt;
}

}  // namespace csgtile::fit::detail
