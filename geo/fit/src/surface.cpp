// Surfaces of the RANSAC: distances and normals, candidates from minimal samples with normals,
// and least-squares refits.

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numbers>

#include "fit_internal.h"

namespace csgtile::fit {

const char* shape_type_name(ShapeType type) {
  switch (type) {
    case ShapeType::Plane:
      return "plane";
    case ShapeType::Sphere:
      return "sphere";
    case ShapeType::Cylinder:
      return "cylinder";
    case ShapeType::Cone:
      return "cone";
    case ShapeType::Torus:
      return "torus";
  }
  return "unknown";
}

namespace {

using kernel::Vec3;

// Radial part of v about the axis: v minus its axial component.
Vec3 radial(const Vec3& v, const Vec3& axis) { return v - v.dot(axis) * axis; }

// Unit direction of the radial part `w` (of length `len`); on the axis, any direction across it.
Vec3 outward(const Vec3& w, double len, const Vec3& axis) {
  if (len > 0.0) return w / len;
  Vec3 e1, e2;
  detail::orthonormal_basis(axis, e1, e2);
  return e1;
}

}  // namespace

double surface_distance(const Surface& s, const Vec3& p) {
  const Vec3 v = p - s.point;
  switch (s.type) {
    case ShapeType::Plane:
      return v.dot(s.axis);
    case ShapeType::Sphere:
      return v.norm() - s.radius;
    case ShapeType::Cylinder:
      return radial(v, s.axis).norm() - s.radius;
    case ShapeType::Cone: {
      const double h = v.dot(s.axis);
      const double rho = radial(v, s.axis).norm();
      // In the (rho, h) half-plane the cone is the ray at angle `angle` from the axis; behind
      // the apex the nearest point is the apex itself.
      const double along = rho * std::sin(s.angle) + h * std::cos(s.angle);
      if (along < 0.0) return v.norm();
      return rho * std::cos(s.angle) - h * std::sin(s.angle);
    }
    case ShapeType::Torus: {
      const double h = v.dot(s.axis);
      const double rho = radial(v, s.axis).norm();
      return std::hypot(rho - s.radius, h) - s.radius2;
    }
  }
  return 0.0;
}

Vec3 surface_normal(const Surface& s, const Vec3& p) {
  const Vec3 v = p - s.point;
  switch (s.type) {
    case ShapeType::Plane:
      return s.axis;
    case ShapeType::Sphere: {
      const double len = v.norm();
      return len > 0.0 ? Vec3(v / len) : s.axis;
    }
    case ShapeType::Cylinder: {
      const Vec3 w = radial(v, s.axis);
      const double len = w.norm();
      return len > 0.0 ? Vec3(w / len) : s.axis;
    }
    case ShapeType::Cone: {
      const Vec3 w = radial(v, s.axis);
      const double len = w.norm();
      const Vec3 out_dir = outward(w, len, s.axis);
      return std::cos(s.angle) * out_dir - std::sin(s.angle) * s.axis;
    }
    case ShapeType::Torus: {
      const double h = v.dot(s.axis);
      const Vec3 w = radial(v, s.axis);
      const double rho = w.norm();
      const Vec3 out_dir = outward(w, rho, s.axis);
      const Vec3 q = (rho - s.radius) * out_dir + h * s.axis;
      const double len = q.norm();
      return len > 0.0 ? Vec3(q / len) : out_dir;
    }
  }
  return s.axis;
}

namespace detail {

void orthonormal_basis(const Vec3& axis, Vec3& e1, Vec3& e2) {
  // The coordinate axis least aligned with `axis` gives a well-conditioned first vector.
  const Vec3 a = axis.cwiseAbs();
  Vec3 helper = Vec3::UnitX();
  if (a.y() <= a.x() && a.y() <= a.z()) {
    helper = Vec3::UnitY();
  } else if (a.z() <= a.x() && a.z() <= a.y()) {
    helper = Vec3::UnitZ();
  }
  e1 = axis.cross(helper).normalized();
  e2 = axis.cross(e1);
}

Vec3 canonical_axis(const Vec3& axis) {
  constexpr double kTiny = 1e-12;
  if (axis.z() > kTiny) return axis;
  if (axis.z() < -kTiny) return -axis;
  if (axis.y() > kTiny) return axis;
  if (axis.y() < -kTiny) return -axis;
  return axis.x() >= 0.0 ? axis : Vec3(-axis);
}

namespace {

// Closest points of the lines a + s·u and b + t·v (unit directions); false when parallel.
bool closest_points(const Vec3& a, const Vec3& u, const Vec3& b, const Vec3& v, Vec3& on_a,
                    Vec3& on_b) {
  const Vec3 w0 = a - b;
  const double uv = u.dot(v);
  const double denom = 1.0 - uv * uv;
  if (denom < 1e-6) return false;
  const double d = u.dot(w0);
  const double e = v.dot(w0);
  const double s = (uv * e - d) / denom;
  const double t = (e - uv * d) / denom;
  on_a = a + s * u;
  on_b = b + t * v;
  return true;
}

bool finite(const Surface& s) {
  return s.point.allFinite() && s.axis.allFinite() && std::isfinite(s.radius) &&
         std::isfinite(s.radius2) && std::isfinite(s.angle);
}

}  // namespace

std::optional<Surface> plane_from_samples(std::span<const Vec3> p, std::span<const Vec3> /*n*/) {
  if (p.size() < 3) return std::nullopt;
  const Vec3 a = p[1] - p[0];
  const Vec3 b = p[2] - p[0];
  const Vec3 normal = a.cross(b);
  const double len = normal.norm();
  // Nearly collinear samples give no plane.
  if (!(len > 0.05 * a.norm() * b.norm()) || len == 0.0) return std::nullopt;
  Surface s;
  s.type = ShapeType::Plane;
  s.point = p[0];
  s.axis = normal / len;
  return s;
}

std::optional<Surface> sphere_from_samples(std::span<const Vec3> p, std::span<const Vec3> n,
                                           double max_radius) {
  if (p.size() < 2) return std::nullopt;
  Vec3 c0, c1;
  if (!closest_points(p[0], n[0], p[1], n[1], c0, c1)) return std::nullopt;
  Surface s;
  s.type = ShapeType::Sphere;
  s.point = 0.5 * (c0 + c1);
  s.radius = 0.5 * ((p[0] - s.point).norm() + (p[1] - s.point).norm());
  if (!(s.radius > 0.0 && s.radius < max_radius) || !finite(s)) return std::nullopt;
  return s;
}

std::optional<Surface> cylinder_from_samples(std::span<const Vec3> p, std::span<const Vec3> n,
                                             double max_radius) {
  if (p.size() < 2) return std::nullopt;
  Vec3 axis = n[0].cross(n[1]);
  const double len = axis.norm();
  if (len < 0.05) return std::nullopt;
  axis /= len;
  // Normals of a cylinder are orthogonal to its axis: take their components in the plane
  // orthogonal to it and intersect the normal lines there.
  const Vec3 n0 = radial(n[0], axis).normalized();
  const Vec3 n1 = radial(n[1], axis).normalized();
  const Vec3 q1 = p[1] - (p[1] - p[0]).dot(axis) * axis;  // p1 moved into p0's cross-section
  Vec3 c0, c1;
  if (!closest_points(p[0], n0, q1, n1, c0, c1)) return std::nullopt;
  Surface s;
  s.type = ShapeType::Cylinder;
  s.axis = canonical_axis(axis);
  s.point = 0.5 * (c0 + c1);
  s.radius = 0.5 * (radial(p[0] - s.point, s.axis).norm() + radial(p[1] - s.point, s.axis).norm());
  if (!(s.radius > 0.0 && s.radius < max_radius) || !finite(s)) return std::nullopt;
  return s;
}

std::optional<Surface> cone_from_samples(std::span<const Vec3> p, std::span<const Vec3> n,
                                         double max_radius) {
  if (p.size() < 3) return std::nullopt;
  Eigen::Matrix3d a;
  Eigen::Vector3d b;
  for (int i = 0; i < 3; ++i) {
    a.row(i) = n[static_cast<std::size_t>(i)].transpose();
    b(i) = n[static_cast<std::size_t>(i)].dot(p[static_cast<std::size_t>(i)]);
  }
  // The apex is the common point of the three tangent planes.
  if (std::abs(a.determinant()) < 1e-3) return std::nullopt;
  const Vec3 apex = a.partialPivLu().solve(b);
  Vec3 u[3];
  for (int i = 0; i < 3; ++i) {
    const Vec3 d = p[static_cast<std::size_t>(i)] - apex;
    const double len = d.norm();
    if (!(len > 1e-9) || len > 2.0 * max_radius) return std::nullopt;
    u[i] = d / len;
  }
  Vec3 axis = (u[1] - u[0]).cross(u[2] - u[0]);
  const double len = axis.norm();
  if (!(len > 1e-9)) return std::nullopt;
  axis /= len;
  if (axis.dot(u[0] + u[1] + u[2]) < 0.0) axis = -axis;
  double angle = 0.0;
  for (const auto& ui : u) angle += std::acos(std::clamp(axis.dot(ui), -1.0, 1.0));
  angle /= 3.0;
  constexpr double kDegree = std::numbers::pi / 180.0;
  if (angle < 2.0 * kDegree || angle > 80.0 * kDegree) return std::nullopt;
  Surface s;
  s.type = ShapeType::Cone;
  s.point = apex;
  s.axis = axis;
  s.angle = angle;
  if (!finite(s)) return std::nullopt;
  return s;
}

namespace {

// A line (d, m) in Plücker coordinates meets the normal line (n_i, p_i × n_i) when
// d·(p_i × n_i) + m·n_i = 0: the axis of a surface of revolution is the null vector of those
// rows, the eigenvector of least eigenvalue of their 6 × 6 scatter matrix (a fixed-size
// symmetric eigenproblem: a RANSAC draw proposes a torus from a handful of samples, and a
// Jacobi SVD of the rows cost a tenth of a city fit). The points are taken about their
// centroid c, which keeps the moments small; the moment about the origin is m' + c × d.
Eigen::Matrix<double, 6, 1> revolution_axis(std::span<const Vec3> p, std::span<const Vec3> n) {
  Vec3 c = Vec3::Zero();
  for (const Vec3& q : p) c += q;
  c /= static_cast<double>(p.size());
  Eigen::Matrix<double, 6, 6> scatter = Eigen::Matrix<double, 6, 6>::Zero();
  for (std::size_t i = 0; i < p.size(); ++i) {
    Eigen::Matrix<double, 6, 1> row;
    row << (p[i] - c).cross(n[i]), n[i];
    scatter.noalias() += row * row.transpose();  // fixed size: on the stack
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> eigen(scatter);
  Eigen::Matrix<double, 6, 1> x = eigen.eigenvectors().col(0);
  const Vec3 d = x.head<3>();
  x.tail<3>() += c.cross(d);
  return x;
}

}  // namespace

std::optional<Surface> torus_from_samples(std::span<const Vec3> p, std::span<const Vec3> n,
                                          double max_radius) {
  if (p.size() < 6) return std::nullopt;
  const Eigen::Matrix<double, 6, 1> x = revolution_axis(p, n);
  Vec3 d = x.head<3>();
  Vec3 m = x.tail<3>();
  const double dl = d.norm();
  if (!(dl > 1e-9)) return std::nullopt;
  m /= dl;
  d /= dl;
  const Vec3 q = d.cross(m);  // the axis point nearest the origin
  // Points in the (rho, h) half-plane lie on the meridian circle: fit it algebraically.
  Eigen::MatrixXd c(static_cast<Eigen::Index>(p.size()), 3);
  Eigen::VectorXd rhs(static_cast<Eigen::Index>(p.size()));
  for (std::size_t i = 0; i < p.size(); ++i) {
    const Vec3 v = p[i] - q;
    const double h = v.dot(d);
    const double rho = radial(v, d).norm();
    const auto row = static_cast<Eigen::Index>(i);
    c(row, 0) = rho;
    c(row, 1) = h;
    c(row, 2) = 1.0;
    rhs(row) = -(rho * rho + h * h);
  }
  const Eigen::Vector3d sol = c.colPivHouseholderQr().solve(rhs);
  const double r0 = -0.5 * sol(0);
  const double h0 = -0.5 * sol(1);
  const double minor2 = r0 * r0 + h0 * h0 - sol(2);
  if (!(minor2 > 0.0)) return std::nullopt;
  Surface s;
  s.type = ShapeType::Torus;
  s.axis = canonical_axis(d);
  s.point = q + h0 * d;
  s.radius = r0;
  s.radius2 = std::sqrt(minor2);
  if (!(s.radius2 > 0.0 && s.radius > 1.05 * s.radius2 && s.radius < 0.5 * max_radius) ||
      !finite(s)) {
    return std::nullopt;
  }
  return s;
}

std::optional<PrincipalAxes> principal_axes(std::span<const Vec3> points,
                                            std::span<const std::uint32_t> subset) {
  if (subset.size() < 3) return std::nullopt;
  PrincipalAxes out;
  for (auto i : subset) out.centroid += points[i];
  out.centroid /= static_cast<double>(subset.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (auto i : subset) {
    const Vec3 d = points[i] - out.centroid;
    cov += d * d.transpose();
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  if (eig.info() != Eigen::Success) return std::nullopt;
  out.values = eig.eigenvalues();
  out.axes = eig.eigenvectors();
  return out;
}

std::optional<Surface> fit_plane(std::span<const Vec3> points,
                                 std::span<const std::uint32_t> subset) {
  const auto principal = principal_axes(points, subset);
  if (!principal) return std::nullopt;
  // A plane needs two spread directions.
  if (!(principal->values(1) > 1e-12 * std::max(1.0, principal->values(2)))) return std::nullopt;
  Surface s;
  s.type = ShapeType::Plane;
  s.point = principal->centroid;
  s.axis = canonical_axis(principal->axes.col(0).normalized());
  if (!finite(s)) return std::nullopt;
  return s;
}

int parameter_count(ShapeType type) {
  switch (type) {
    case ShapeType::Plane:
      return 3;
    case ShapeType::Sphere:
      return 4;
    case ShapeType::Cylinder:
      return 5;
    case ShapeType::Cone:
      return 6;
    case ShapeType::Torus:
      return 7;
  }
  return 0;
}

double information_criterion(double rss, double n, double floor, int k, double penalty_n) {
  return n * std::log(std::max(rss / n, floor * floor)) + k * std::log(penalty_n);
}

namespace {

// The surface moved by a small parameter step. Axes turn in the tangent plane of the current
// axis (e1, e2), so the step has no redundant direction.
Surface apply_step(const Surface& s, const Eigen::VectorXd& d) {
  Vec3 e1, e2;
  orthonormal_basis(s.axis, e1, e2);
  Surface out = s;
  switch (s.type) {
    case ShapeType::Plane:
      out.axis = (s.axis + d(0) * e1 + d(1) * e2).normalized();
      out.point = s.point + d(2) * s.axis;
      break;
    case ShapeType::Sphere:
      out.point = s.point + Vec3(d(0), d(1), d(2));
      out.radius = s.radius + d(3);
      break;
    case ShapeType::Cylinder:
      out.axis = (s.axis + d(0) * e1 + d(1) * e2).normalized();
      out.point = s.point + d(2) * e1 + d(3) * e2;
      out.radius = s.radius + d(4);
      break;
    case ShapeType::Cone:
      out.axis = (s.axis + d(0) * e1 + d(1) * e2).normalized();
      out.point = s.point + Vec3(d(2), d(3), d(4));
      out.angle = s.angle + d(5);
      break;
    case ShapeType::Torus:
      out.axis = (s.axis + d(0) * e1 + d(1) * e2).normalized();
      out.point = s.point + Vec3(d(2), d(3), d(4));
      out.radius = s.radius + d(5);
      out.radius2 = s.radius2 + d(6);
      break;
  }
  return out;
}

double cost(const Surface& s, std::span<const Vec3> pts) {
  double sum = 0.0;
  for (const auto& p : pts) {
    const double r = surface_distance(s, p);
    sum += r * r;
  }
  return sum;
}

}  // namespace

std::optional<Surface> refine_surface(const Surface& start, std::span<const Vec3> points,
                                      std::span<const std::uint32_t> subset,
                                      std::size_t max_points) {
  if (start.type == ShapeType::Plane) return fit_plane(points, subset);
  const int k = parameter_count(start.type);
  if (subset.size() < static_cast<std::size_t>(k) + 2) return std::nullopt;
  std::vector<Vec3> pts;
  const std::size_t stride =
      std::max<std::size_t>(1, (subset.size() + max_points - 1) / max_points);
  for (std::size_t i = 0; i < subset.size(); i += stride) pts.push_back(points[subset[i]]);
  const auto n = static_cast<Eigen::Index>(pts.size());

  Surface current = start;
  double current_cost = cost(current, pts);
  double lambda = 1e-3;
  const double scale = std::max({1e-3, start.radius, start.radius2});
  for (int iteration = 0; iteration < 20; ++iteration) {
    Eigen::VectorXd r(n);
    for (Eigen::Index i = 0; i < n; ++i)
      r(i) = surface_distance(current, pts[static_cast<std::size_t>(i)]);
    Eigen::MatrixXd jac(n, k);
    for (int j = 0; j < k; ++j) {
      Eigen::VectorXd step = Eigen::VectorXd::Zero(k);
      // Angles are dimensionless, lengths scale with the surface.
      const bool is_angle =
          (j < 2 && start.type != ShapeType::Sphere) || (start.type == ShapeType::Cone && j == 5);
      const double h = is_angle ? 1e-7 : 1e-7 * scale;
      step(j) = h;
      const Surface moved = apply_step(current, step);
      for (Eigen::Index i = 0; i < n; ++i) {
        jac(i, j) = (surface_distance(moved, pts[static_cast<std::size_t>(i)]) - r(i)) / h;
      }
    }
    const Eigen::MatrixXd jtj = jac.transpose() * jac;
    const Eigen::VectorXd jtr = jac.transpose() * r;
    bool improved = false;
    for (int attempt = 0; attempt < 8; ++attempt) {
      Eigen::MatrixXd lhs = jtj;
      for (int j = 0; j < k; ++j) lhs(j, j) += lambda * std::max(jtj(j, j), 1e-12);
      const Eigen::VectorXd delta = lhs.ldlt().solve(-jtr);
      if (!delta.allFinite()) break;
      const Surface candidate = apply_step(current, delta);
      const double c = cost(candidate, pts);
      if (std::isfinite(c) && c < current_cost) {
        const bool converged = current_cost - c < 1e-12 * (1.0 + current_cost);
        current = candidate;
        current_cost = c;
        lambda = std::max(lambda * 0.3, 1e-9);
        improved = !converged;
        break;
      }
      lambda *= 10.0;
    }
    if (!improved) break;
  }
  if (!finite(current)) return std::nullopt;
  if (current.type == ShapeType::Cylinder || current.type == ShapeType::Torus) {
    current.axis = canonical_axis(current.axis);
  }
  if (current.radius < 0.0 || current.radius2 < 0.0) return std::nullopt;
  if (current.type == ShapeType::Cone &&
      !(current.angle > 0.0 && current.angle < std::numbers::pi / 2)) {
    return std::nullopt;
  }
  return current;
}

}  // namespace detail

}  // namespace csgtile::fit
