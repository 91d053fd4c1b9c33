// Exact points no shape took (RansacOptions on exact clouds): the surfaces they lie on,
// though the search could not see them by their normals or they are too few for min_points.

#include <algorithm>
#include <cmath>
#include <optional>
#include <vector>

#include <Eigen/Dense>

#include "ransac_detector.h"

namespace csgtile::fit::detail {

namespace {

// The circle through three points of a plane: its centre and radius; nullopt when they lie on
// one line.
std::optional<std::pair<kernel::Vec2, double>> circle_through(const kernel::Vec2& a,
                                                              const kernel::Vec2& b,
                                                              const kernel::Vec2& c) {
  const kernel::Vec2 u = b - a, v = c - a;
  const double d = 2.0 * (u.x() * v.y() - u.y() * v.x());
  const double scale = u.squaredNorm() * v.squaredNorm();
  if (!(d * d > 1e-18 * scale)) return std::nullopt;
  const double uu = u.squaredNorm(), vv = v.squaredNorm();
  const kernel::Vec2 centre(a.x() + (v.y() * uu - u.y() * vv) / d,
                            a.y() + (u.x() * vv - v.x() * uu) / d);
  return std::make_pair(centre, (centre - a).norm());
}

// The sphere through four points; nullopt when they lie on one plane.
std::optional<std::pair<Vec3, double>> sphere_through(const Vec3& a, const Vec3& b, const Vec3& c,
                                                      const Vec3& d) {
  Eigen::Matrix3d m;
  m.row(0) = (b - a).transpose();
  m.row(1) = (c - a).transpose();
  m.row(2) = (d - a).transpose();
  const double size = std::max({(b - a).norm(), (c - a).norm(), (d - a).norm()});
  const double det = m.determinant();
  if (!(std::abs(det) > 1e-9 * size * size * size)) return std::nullopt;
  const Vec3 rhs(0.5 * (b - a).squaredNorm(), 0.5 * (c - a).squaredNorm(),
                 0.5 * (d - a).squaredNorm());
  const Vec3 centre = a + m.inverse() * rhs;
  return std::make_pair(centre, (centre - a).norm());
}

}  // namespace

// Before the leftovers are fitted, on an exact cloud: a shape the second search left as a
// compromise between surfaces (a rounded edge's cylinder that took the rounded corners at its
// ends, refitted through them a few thousandths too wide) whose best half fits its surface
// exactly becomes that surface, and frees the points off it (beyond an exact fit's reach),
// for fit_leftovers to find their own surfaces; the ones it leaves free adopt_free gives back.
// Shapes that fit most of their points exactly already, or none, are left as they are. The
// number of points freed.
std::size_t Detector::trim_to_exact_cores() {
  std::size_t freed = 0;
  for (auto& shape : shapes_) {
    if (shape.inliers.empty() || exact_fit(rms_of(shape.surface, shape.inliers))) continue;
    const auto core = exact_half(shape);
    if (!core || core->surface.type != shape.surface.type) continue;
    const double reach = exact_reach(core->rms);
    std::vector<std::uint32_t> kept, off;
    for (auto i : shape.inliers) {
      (std::abs(surface_distance(core->surface, points_[i])) <= reach ? kept : off).push_back(i);
    }
    if (static_cast<long long>(kept.size()) < o_.min_points) continue;  // no shape: as it was
    for (auto i : off) assignment_[i] = -1;
    freed += off.size();
    shape.surface = core->surface;
    shape.inliers = std::move(kept);
  }
  return freed;
}

// On exact clouds, connected points no shape holds (min_points or more) whose normals the
// search could not use (a small hole's wall sampled between the plates' rims: each point's
// neighbours are mostly rim points, its normal the plates') may still lie on one surface: the
// plane through them, or the cylinder across one of their neighbours' planes (a hole runs
// across the plate it pierces) or along a neighbouring cylinder's axis, when it fits them to
// the noise floor, becomes a shape of the points within kOnSurfaceFloors floors of it. The
// number of shapes added.
std::size_t Detector::fit_leftovers() {
  const double floor = noise_floor();
  std::size_t added = 0;
  std::vector<char> seen(points_.size(), 0);
  for (std::uint32_t start = 0; start < points_.size(); ++start) {
    if (assignment_[start] >= 0 || seen[start] || grid_->cell_of(start) < 0) continue;
    // The free points connected to `start` (through the connectivity grid's neighbourhoods).
    std::vector<std::uint32_t> group{start};
    seen[start] = 1;
    std::vector<Vec3> axes;
    for (std::size_t h = 0; h < group.size(); ++h) {
      const std::uint32_t one[1] = {group[h]};
      for_points_near(one, [&](std::uint32_t j) {
        const int a = assignment_[j];
        if (a >= 0) {
          const Surface& s = shapes_[static_cast<std::size_t>(a)].surface;
          if (s.type == ShapeType::Plane || s.type == ShapeType::Cylinder) {
            const bool known = std::any_of(axes.begin(), axes.end(), [&](const Vec3& x) {
              return std::abs(x.dot(s.axis)) > 0.9999;
            });
            if (!known) axes.push_back(s.axis);
          }
          return;
        }
        if (seen[j]) return;
        seen[j] = 1;
        group.push_back(j);
      });
    }
    std::sort(group.begin(), group.end());
    if (static_cast<long long>(group.size()) < o_.min_points) {
      added += small_exact_shapes(group, axes);
      continue;
    }
    std::optional<Surface> best;
    if (auto plane = detail::fit_plane(points_, group); plane && rms_of(*plane, group) <= floor) {
      best = plane;
    }
    for (const Vec3& axis : axes) {
      if (best) break;
      auto cylinder = circle_along(axis, group);
      if (cylinder) cylinder = detail::refine_surface(*cylinder, points_, group);
      if (cylinder && cylinder->radius < o_.max_radius && rms_of(*cylinder, group) <= floor) {
        best = cylinder;
      }
    }
    if (!best) {
      added += small_exact_shapes(group, axes);
      continue;
    }
    DetectedShape shape;
    shape.surface = *best;
    for (auto i : group) {
      if (std::abs(surface_distance(*best, points_[i])) <= kOnSurfaceFloors * floor) {
        shape.inliers.push_back(i);
      }
    }
    if (static_cast<long long>(shape.inliers.size()) < o_.min_points) continue;
    for (auto i : shape.inliers) assignment_[i] = static_cast<int>(shapes_.size());
    shape.rms = rms_of(shape.surface, shape.inliers);
    shapes_.push_back(std::move(shape));
    ++added;
  }
  return added;
}

// Exact points too few for min_points, or of several surfaces (a rounded edge's free points
// and the rounded corners at its two ends, all connected; a flat strip between two arcs whose
// one free column lies between the rims the arcs hold), still lie on their surfaces. With the
// shapes' points next to them (rims lie on both surfaces), the plane through three of these
// points, the cylinder along a neighbouring shape's axis through three, or the sphere through
// four, that most of them lie on (within an exact fit's reach) is a shape of the free points on
// it, where more lie on it than fix it: for the plane, four positions more than epsilon apart
// not all on two lines (any two parallel lines are coplanar: two columns of a cylinder's wall);
// for the circle across the axis four positions; for the sphere six, not all on one plane.
// At least three free points not on an existing shape's surface must be on it. Found one after
// another, the most supported first (a plane, then a cylinder, then a sphere, as well
// supported); a point on two of them (where a corner's sphere meets the edge's cylinder)
// counts for both and stays with the first; edges_to_smaller later gives the new shapes their
// rims. Groups with more than kSmallGroup points with their neighbours are left as they are
// (the search is exhaustive). The number of shapes added.
std::size_t Detector::small_exact_shapes(std::span<const std::uint32_t> group,
                                         const std::vector<Vec3>& axes) {
  constexpr std::size_t kSmallGroup = 48;
  const std::size_t m = group.size();
  if (m < 3 || m > kSmallGroup) return 0;
  // The pool: the free points, then the shapes' points next to them (each free point's
  // kHeldNear nearest), when there are not too many.
  constexpr std::size_t kHeldNear = 4;
  std::vector<std::uint32_t> pool(group.begin(), group.end());
  {
    std::vector<std::uint32_t> near;
    for_points_near(group, [&](std::uint32_t j) {
      if (assignment_[j] >= 0) near.push_back(j);
    });
    std::vector<std::uint32_t> held;
    std::vector<std::pair<double, std::uint32_t>> by_distance;
    for (const std::uint32_t i : group) {
      by_distance.clear();
      for (const std::uint32_t j : near)
        by_distance.emplace_back((points_[j] - points_[i]).norm(), j);
      const std::size_t keep = std::min(kHeldNear, by_distance.size());
      std::partial_sort(by_distance.begin(),
                        by_distance.begin() + static_cast<std::ptrdiff_t>(keep), by_distance.end());
      for (std::size_t k = 0; k < keep; ++k) held.push_back(by_distance[k].second);
    }
    std::sort(held.begin(), held.end());
    held.erase(std::unique(held.begin(), held.end()), held.end());
    if (m + held.size() <= kSmallGroup) pool.insert(pool.end(), held.begin(), held.end());
  }
  const std::size_t n = pool.size();
  // Exact: through points that fix it, the others within the reach of an exact fit.
  const double tol = exact_reach(0.0);
  const double apart = o_.epsilon;
  std::vector<char> taken(n, 0);
  for (std::size_t k = m; k < n; ++k) taken[k] = 1;  // held by their shapes
  auto support = [&](const Surface& s) {
    std::vector<std::size_t> on;
    for (std::size_t k = 0; k < n; ++k) {
      if (std::abs(surface_distance(s, points_[pool[k]])) <= tol) on.push_back(k);
    }
    return on;
  };
  // How many of `pos` lie more than `apart` from each other (greedy, in order).
  auto distinct = [&](const auto& pos) {
    std::vector<std::size_t> kept;
    for (std::size_t k = 0; k < pos.size(); ++k) {
      const bool near = std::any_of(kept.begin(), kept.end(), [&](std::size_t j) {
        return (pos[j] - pos[k]).norm() <= apart;
      });
      if (!near) kept.push_back(k);
    }
    return kept.size();
  };
  // Whether the points all lie on at most two lines (within `apart`).
  auto on_two_lines = [&](const std::vector<Vec3>& at) {
    auto on_line = [&](const Vec3& a, const Vec3& b, const Vec3& q) {
      const Vec3 u = (b - a).normalized();
      const Vec3 d = q - a;
      return (d - d.dot(u) * u).norm() <= apart;
    };
    for (std::size_t i = 0; i < at.size(); ++i) {
      for (std::size_t j = i + 1; j < at.size(); ++j) {
        if ((at[j] - at[i]).norm() <= apart) continue;
        std::vector<Vec3> rest;
        for (const Vec3& q : at) {
          if (!on_line(at[i], at[j], q)) rest.push_back(q);
        }
        if (rest.size() <= 1) return true;
        std::size_t far = 1;
        while (far < rest.size() && (rest[far] - rest[0]).norm() <= apart) ++far;
        if (far == rest.size()) return true;
        if (std::all_of(rest.begin(), rest.end(),
                        [&](const Vec3& q) { return on_line(rest[0], rest[far], q); })) {
          return true;
        }
      }
    }
    return false;
  };
  std::size_t added = 0;
  for (;;) {
    std::optional<Surface> best;
    std::vector<std::size_t> best_on;
    int best_rank = 0;
    auto consider = [&](const Surface& s, int rank) {
      if (s.type != ShapeType::Plane && !(s.radius > 0.0 && s.radius < o_.max_radius)) return;
      std::vector<std::size_t> on = support(s);
      // Ranked by support, then the plane, cylinder, sphere, then found first.
      if (best &&
          (on.size() < best_on.size() || (on.size() == best_on.size() && rank >= best_rank))) {
        return;
      }
      // Its own points: free, and not on the surface of a shape it shares points with (that
      // shape is the surface they lie on; adopt_free gives them to it).
      std::vector<std::size_t> own;
      std::vector<int> neighbours;
      for (std::size_t k : on) {
        if (!taken[k]) own.push_back(k);
        if (k >= m) neighbours.push_back(assignment_[pool[k]]);
      }
      std::sort(neighbours.begin(), neighbours.end());
      neighbours.erase(std::unique(neighbours.begin(), neighbours.end()), neighbours.end());
      std::erase_if(own, [&](std::size_t k) {
        return std::any_of(neighbours.begin(), neighbours.end(), [&](int a) {
          return std::abs(surface_distance(shapes_[static_cast<std::size_t>(a)].surface,
                                           points_[pool[k]])) <= tol;
        });
      });
      if (own.size() < 3) return;
      std::vector<Vec3> at;
      for (std::size_t k : on) at.push_back(points_[pool[k]]);
      if (s.type == ShapeType::Plane) {
        if (distinct(at) < 4 || on_two_lines(at)) return;
      } else if (s.type == ShapeType::Cylinder) {
        Vec3 e1, e2;
        detail::orthonormal_basis(s.axis, e1, e2);
        std::vector<kernel::Vec2> across;
        for (const Vec3& q : at) across.emplace_back(q.dot(e1), q.dot(e2));
        if (distinct(across) < 4) return;
      } else {
        if (distinct(at) < 6) return;
        std::vector<std::uint32_t> idx;
        for (std::size_t k : on) idx.push_back(pool[k]);
        const auto plane = detail::fit_plane(points_, idx);
        if (plane && rms_of(*plane, idx) <= tol) return;  // one plane: no sphere told apart
      }
      best = s;
      best_on = std::move(on);
      best_rank = rank;
    };
    // Each surface is drawn through at least one free point not yet taken.
    auto fresh = [&](std::size_t i) { return i < m && !taken[i]; };
    for (std::size_t i = 0; i < n; ++i) {
      for (std::size_t j = i + 1; j < n; ++j) {
        for (std::size_t k = j + 1; k < n; ++k) {
          if (!fresh(i) && !fresh(j) && !fresh(k)) continue;
          const Vec3 &a = points_[pool[i]], &b = points_[pool[j]], &c = points_[pool[k]];
          const Vec3 normal = (b - a).cross(c - a);
          if (!(normal.norm() > apart * apart)) continue;  // on one line
          Surface s;
          s.type = ShapeType::Plane;
          s.point = a;
          s.axis = detail::canonical_axis(normal.normalized());
          consider(s, 0);
        }
      }
    }
    for (const Vec3& axis : axes) {
      Vec3 e1, e2;
      detail::orthonormal_basis(axis, e1, e2);
      std::vector<kernel::Vec2> across;
      for (std::size_t k = 0; k < n; ++k)
        across.emplace_back(points_[pool[k]].dot(e1), points_[pool[k]].dot(e2));
      for (std::size_t i = 0; i < n; ++i) {
        for (std::size_t j = i + 1; j < n; ++j) {
          if ((across[j] - across[i]).norm() <= apart) continue;
          for (std::size_t k = j + 1; k < n; ++k) {
            if (!fresh(i) && !fresh(j) && !fresh(k)) continue;
            const auto circle = circle_through(across[i], across[j], across[k]);
            if (!circle) continue;
            Surface s;
            s.type = ShapeType::Cylinder;
            s.axis = detail::canonical_axis(axis);
            s.point = circle->first.x() * e1 + circle->first.y() * e2;
            s.radius = circle->second;
            consider(s, 1);
          }
        }
      }
    }
    for (std::size_t i = 0; i < n; ++i) {
      for (std::size_t j = i + 1; j < n; ++j) {
        for (std::size_t k = j + 1; k < n; ++k) {
          for (std::size_t l = k + 1; l < n; ++l) {
            if (!fresh(i) && !fresh(j) && !fresh(k) && !fresh(l)) continue;
            const auto sphere = sphere_through(points_[pool[i]], points_[pool[j]], points_[pool[k]],
                                               points_[pool[l]]);
            if (!sphere) continue;
            Surface s;
            s.type = ShapeType::Sphere;
            s.point = sphere->first;
            s.radius = sphere->second;
            consider(s, 2);
          }
        }
      }
    }
    if (!best) break;
    // Refined on all the points it holds, when that keeps them on it.
    std::vector<std::uint32_t> on_points;
    for (std::size_t k : best_on) on_points.push_back(pool[k]);
    if (auto refined = best->type == ShapeType::Plane
                           ? detail::fit_plane(points_, on_points)
                           : detail::refine_surface(*best, points_, on_points);
        refined && (refined->type == ShapeType::Plane || refined->radius < o_.max_radius) &&
        exact_fit(rms_of(*refined, on_points))) {
      if (std::vector<std::size_t> on = support(*refined); on.size() >= best_on.size()) {
        best = *refined;
        best_on = std::move(on);
      }
    }
    DetectedShape shape;
    shape.surface = *best;
    for (std::size_t k : best_on) {
      if (taken[k]) continue;
      taken[k] = 1;
      shape.inliers.push_back(pool[k]);
      assignment_[pool[k]] = static_cast<int>(shapes_.size());
    }
    shape.rms = rms_of(shape.surface, shape.inliers);
    shapes_.push_back(std::move(shape));
    ++added;
  }
  return added;
}

}  // namespace csgtile::fit::detail
