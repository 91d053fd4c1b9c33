// From detected surfaces to scene primitives. Boxes come from planes: a seed plane whose
// points fill their bounding rectangle, the nearest parallel plane facing it across the box
// (or, when none is seen, the points of orthogonal planes along its rectangle), so that a beam
// scanned on two or three sides is one box. Curved surfaces are bounded by their inliers.
// Every primitive is built as a kernel solid and checked before it is kept.

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <numbers>
#include <set>
#include <tuple>

#include "csgtile/kernel/check.h"
#include "fit/fit_internal.h"

namespace csgtile::geo {

namespace {

using kernel::Location;
using kernel::PrimitiveSpec;
using kernel::PrimitiveType;
using kernel::Vec2;
using kernel::Vec3;

// A plane's points in its own frame: n its normal, (u, v) the sides of the smallest
// rectangle around its points.
struct PlanePatch {
  int shape = -1;
  std::vector<std::uint32_t> members;  // a connected piece of the shape's inliers
  Vec3 origin, n, u, v;
  double umin = 0, umax = 0, vmin = 0, vmax = 0;
  double coverage = 0.0;
  bool used = false;
};

double cross2(const Vec2& o, const Vec2& a, const Vec2& b) {
  return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
}

// Convex hull (Andrew's monotone chain), counter-clockwise, no repeated point.
std::vector<Vec2> convex_hull(std::vector<Vec2> pts) {
  std::sort(pts.begin(), pts.end(), [](const Vec2& a, const Vec2& b) {
    return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
  });
  pts.erase(std::unique(pts.begin(), pts.end()), pts.end());
  if (pts.size() < 3) return pts;
  std::vector<Vec2> hull(2 * pts.size());
  std::size_t k = 0;
  for (const auto& p : pts) {
    while (k >= 2 && cross2(hull[k - 2], hull[k - 1], p) <= 0) --k;
    hull[k++] = p;
  }
  for (std::size_t i = pts.size() - 1, t = k + 1; i-- > 0;) {
    while (k >= t && cross2(hull[k - 2], hull[k - 1], pts[i]) <= 0) --k;
    hull[k++] = pts[i];
  }
  hull.resize(k - 1);
  return hull;
}

// The plane's inliers split into pieces connected in the plane at the scale of their own
// spacing: coplanar faces of neighbouring boxes (a row of beams between columns) that the
// RANSAC's coarser connectivity joined come apart at the gaps between them.
std::vector<std::vector<std::uint32_t>> split_plane(std::span<const Vec3> points,
                                                    const DetectedShape& shape, double epsilon) {
  const double cell = std::max(detail::neighbour_reach(points, shape.inliers, 0.5) / 2.0, epsilon);
  Vec3 e1, e2;
  detail::orthonormal_basis(shape.surface.axis, e1, e2);
  std::map<std::pair<long long, long long>, std::vector<std::uint32_t>> cells;
  for (auto i : shape.inliers) {
    const Vec3 d = points[i] - shape.surface.point;
    cells[{detail::cell_index(d.dot(e1), cell), detail::cell_index(d.dot(e2), cell)}].push_back(i);
  }
  std::vector<std::vector<std::uint32_t>> pieces;
  std::set<std::pair<long long, long long>> seen;
  for (const auto& [key, ignored] : cells) {
    if (seen.count(key) != 0) continue;
    std::vector<std::pair<long long, long long>> queue{key};
    seen.insert(key);
    std::vector<std::uint32_t> piece;
    for (std::size_t head = 0; head < queue.size(); ++head) {
      const auto k = queue[head];
      const auto& pts = cells.at(k);
      piece.insert(piece.end(), pts.begin(), pts.end());
      for (long long dx = -1; dx <= 1; ++dx) {
        for (long long dy = -1; dy <= 1; ++dy) {
          const std::pair<long long, long long> next{k.first + dx, k.second + dy};
          if (cells.count(next) == 0 || seen.count(next) != 0) continue;
          seen.insert(next);
          queue.push_back(next);
        }
      }
    }
    std::sort(piece.begin(), piece.end());
    pieces.push_back(std::move(piece));
  }
  return pieces;
}

PlanePatch make_patch(std::span<const Vec3> points, const DetectedShape& shape, int index,
                      std::vector<std::uint32_t> members, double cell) {
  PlanePatch patch;
  patch.shape = index;
  patch.members = std::move(members);
  patch.n = shape.surface.axis;
  patch.origin = shape.surface.point;
  Vec3 e1, e2;
  detail::orthonormal_basis(patch.n, e1, e2);
  std::vector<Vec2> flat;
  flat.reserve(patch.members.size());
  for (auto i : patch.members) {
    const Vec3 d = points[i] - patch.origin;
    flat.emplace_back(d.dot(e1), d.dot(e2));
  }
  const auto hull = convex_hull(flat);
  // The smallest rectangle has a side along a hull edge (rotating calipers, by brute force).
  double best_area = INFINITY;
  Vec2 best_dir(1, 0);
  for (std::size_t k = 0; k < hull.size(); ++k) {
    Vec2 dir = hull[(k + 1) % hull.size()] - hull[k];
    if (dir.norm() <= 0.0) continue;
    dir.normalize();
    const Vec2 perp(-dir.y(), dir.x());
    double a0 = INFINITY, a1 = -INFINITY, b0 = INFINITY, b1 = -INFINITY;
    for (const auto& h : hull) {
      a0 = std::min(a0, h.dot(dir));
      a1 = std::max(a1, h.dot(dir));
      b0 = std::min(b0, h.dot(perp));
      b1 = std::max(b1, h.dot(perp));
    }
    const double area = (a1 - a0) * (b1 - b0);
    if (area < best_area - 1e-12) {
      best_area = area;
      best_dir = dir;
    }
  }
  patch.u = best_dir.x() * e1 + best_dir.y() * e2;
  patch.v = patch.n.cross(patch.u);
  patch.umin = patch.vmin = INFINITY;
  patch.umax = patch.vmax = -INFINITY;
  std::set<std::pair<long long, long long>> cells;
  for (auto i : patch.members) {
    const Vec3 d = points[i] - patch.origin;
    const double a = d.dot(patch.u), b = d.dot(patch.v);
    patch.umin = std::min(patch.umin, a);
    patch.umax = std::max(patch.umax, a);
    patch.vmin = std::min(patch.vmin, b);
    patch.vmax = std::max(patch.vmax, b);
    cells.emplace(detail::cell_index(a, cell), detail::cell_index(b, cell));
  }
  if (patch.umax - patch.umin < patch.vmax - patch.vmin) {
    // u along the longer side: (u, v) → (v, -u) keeps the frame right-handed.
    const Vec3 u = patch.u;
    patch.u = patch.v;
    patch.v = -u;
    const double v0 = patch.vmin, v1 = patch.vmax;
    patch.vmin = -patch.umax;
    patch.vmax = -patch.umin;
    patch.umin = v0;
    patch.umax = v1;
  }
  const double rect_cells = std::max(1.0, std::ceil((patch.umax - patch.umin) / cell)) *
                            std::max(1.0, std::ceil((patch.vmax - patch.vmin) / cell));
  patch.coverage = std::min(1.0, static_cast<double>(cells.size()) / rect_cells);
  return patch;
}

// Share of voxels of size `cell` the points occupy, against the area of the primitive's
// surface: an estimate of how much of the primitive the scan saw.
double coverage_of(std::span<const Vec3> points, const std::vector<std::uint32_t>& members,
                   double cell, double area) {
  if (!(area > 0.0) || members.empty()) return 0.0;
  std::set<std::tuple<long long, long long, long long>> voxels;
  for (auto i : members) {
    voxels.emplace(detail::cell_index(points[i].x(), cell), detail::cell_index(points[i].y(), cell),
                   detail::cell_index(points[i].z(), cell));
  }
  return std::min(1.0, static_cast<double>(voxels.size()) * cell * cell / area);
}

// A rotation with columns x, y, x × y, made exactly orthonormal.
Eigen::Matrix3d frame(const Vec3& x, const Vec3& y) {
  const Vec3 ex = x.normalized();
  const Vec3 ey = (y - y.dot(ex) * ex).normalized();
  Eigen::Matrix3d r;
  r.col(0) = ex;
  r.col(1) = ey;
  r.col(2) = ex.cross(ey);
  return r;
}

std::optional<Location> placement(const Eigen::Matrix3d& rotation, const Vec3& origin) {
  kernel::Matrix34 q;
  q.leftCols<3>() = rotation;
  q.col(3) = origin;
  auto loc = Location::from_matrix(q);
  if (!loc.ok()) return std::nullopt;
  return loc.value();
}

class Builder {
 public:
  Builder(std::span<const Vec3> points, const RansacResult& shapes, const PrimitiveOptions& o,
          const RansacOptions& ransac, int region)
      : points_(points),
        shapes_(shapes),
        o_(o),
        ransac_(ransac),
        region_(region),
        used_(points.size(), 0) {
    cos_tol_ = std::cos(o.angle_tolerance_deg * std::numbers::pi / 180.0);
    cell_ = shapes.cluster_epsilon > 0.0 ? shapes.cluster_epsilon : 3.0 * ransac.epsilon;
  }

  FittedPrimitives run();

 private:
  void boxes();
  void curved(int index);
  void emit(PrimitiveSpec spec, const std::vector<std::uint32_t>& members, double area,
            const std::string& what);

  std::span<const Vec3> points_;
  const RansacResult& shapes_;
  PrimitiveOptions o_;
  RansacOptions ransac_;
  int region_;
  double cos_tol_ = 1.0;
  double cell_ = 0.1;
  std::vector<char> used_;
  std::vector<PlanePatch> patches_;
  FittedPrimitives out_;
};

void Builder::emit(PrimitiveSpec spec, const std::vector<std::uint32_t>& members, double area,
                   const std::string& what) {
  auto solid = kernel::build_primitive(spec, o_.linear_tolerance);
  if (!solid.ok()) {
    out_.rejected.push_back({what, std::string("kernel: ") + solid.error().message,
                             static_cast<long long>(members.size())});
    return;
  }
  const auto report = kernel::check_shape(solid.value());
  if (!report.valid()) {
    out_.rejected.push_back({what, std::string("invalid solid: ") + report.issues.front().message,
                             static_cast<long long>(members.size())});
    return;
  }
  ScenePrimitive p;
  p.spec = std::move(spec);
  p.id = "r" + std::to_string(region_) + "-" + std::to_string(out_.primitives.size());
  FitQuality q;
  q.inliers = static_cast<long long>(members.size());
  double sum = 0.0;
  std::size_t counted = 0;
  for (auto i : members) {
    const int s = shapes_.assignment[i];
    if (s < 0) continue;
    const double d =
        surface_distance(shapes_.shapes[static_cast<std::size_t>(s)].surface, points_[i]);
    sum += d * d;
    ++counted;
  }
  q.rms = counted > 0 ? std::sqrt(sum / static_cast<double>(counted)) : 0.0;
  q.coverage = coverage_of(points_, members, cell_, area);
  p.quality = q;
  ++out_.per_type[static_cast<std::size_t>(p.spec.type)];
  out_.assigned_points += q.inliers;
  for (auto i : members) used_[i] = 1;
  out_.primitives.push_back(std::move(p));
}

void Builder::boxes() {
  std::vector<int> order;
  for (std::size_t s = 0; s < shapes_.shapes.size(); ++s) {
    if (shapes_.shapes[s].surface.type != ShapeType::Plane) continue;
    for (auto& piece : split_plane(points_, shapes_.shapes[s], ransac_.epsilon)) {
      if (static_cast<long long>(piece.size()) < std::max<long long>(3, ransac_.min_points / 4)) {
        continue;
      }
      patches_.push_back(
          make_patch(points_, shapes_.shapes[s], static_cast<int>(s), std::move(piece), cell_));
      order.push_back(static_cast<int>(patches_.size() - 1));
    }
  }
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
    return patches_[static_cast<std::size_t>(a)].members.size() >
           patches_[static_cast<std::size_t>(b)].members.size();
  });
  const double margin = std::max(2.0 * ransac_.epsilon, cell_);
  for (int seed_index : order) {
    PlanePatch& seed = patches_[static_cast<std::size_t>(seed_index)];
    if (seed.used || seed.coverage < o_.min_seed_coverage) continue;
    auto local = [&](const Vec3& p) {
      const Vec3 d = p - seed.origin;
      return Vec3(d.dot(seed.u), d.dot(seed.v), d.dot(seed.n));
    };
    auto inside_rect = [&](const Vec3& c, double m) {
      return c.x() >= seed.umin - m && c.x() <= seed.umax + m && c.y() >= seed.vmin - m &&
             c.y() <= seed.vmax + m;
    };
    // Points of the faces sharing the seed's long edge (normal along v, lying along u):
    // within the long edge (shrunk, so that crossing boxes at its ends stay out), anywhere
    // across the short side (grown: those faces lie on its boundary). Their depths (c) say
    // how far the box reaches behind or before the seed.
    std::vector<double> bridge;
    for (const auto& other : patches_) {
      if (other.used || &other == &seed) continue;
      if (std::abs(other.n.dot(seed.v)) < cos_tol_) continue;
      double a0 = INFINITY, a1 = -INFINITY;
      for (auto i : other.members) {
        const double a = (points_[i] - seed.origin).dot(seed.u);
        a0 = std::min(a0, a);
        a1 = std::max(a1, a);
      }
      const double overlap = std::min(a1, seed.umax) - std::max(a0, seed.umin);
      if (overlap < 0.5 * std::min(a1 - a0, seed.umax - seed.umin)) continue;
      for (auto i : other.members) {
        const Vec3 c = local(points_[i]);
        if (c.x() < seed.umin + margin || c.x() > seed.umax - margin ||
            c.y() < seed.vmin - margin || c.y() > seed.vmax + margin ||
            std::abs(c.z()) > o_.max_box_depth) {
          continue;
        }
        bridge.push_back(c.z());
      }
    }
    // Share of the depth interval [0, depth] that the bridging faces' points cover.
    auto bridged = [&](double depth) {
      const int bins = std::max(1, static_cast<int>(std::ceil(std::abs(depth) / cell_)));
      std::vector<char> hit(static_cast<std::size_t>(bins), 0);
      for (double c : bridge) {
        if (c * depth < 0.0 || std::abs(c) > std::abs(depth)) continue;
        const int k = std::min(bins - 1, static_cast<int>(std::abs(c) / cell_));
        hit[static_cast<std::size_t>(k)] = 1;
      }
      return static_cast<double>(std::count(hit.begin(), hit.end(), 1)) / bins;
    };
    // The nearest parallel plane overlapping the seed's rectangle faces it across the box,
    // when faces along the long edge bridge the gap (or none is seen and the gap is small).
    int opposite = -1;
    double opposite_depth = INFINITY;
    for (std::size_t k = 0; k < patches_.size(); ++k) {
      const PlanePatch& other = patches_[k];
      if (static_cast<int>(k) == seed_index || other.used) continue;
      if (std::abs(other.n.dot(seed.n)) < cos_tol_) continue;
      const auto& inl = other.members;
      std::size_t over = 0;
      double depth = 0.0;
      for (auto i : inl) {
        const Vec3 c = local(points_[i]);
        depth += c.z();
        over += inside_rect(c, 0.0) ? 1 : 0;
      }
      depth /= static_cast<double>(inl.size());
      if (std::abs(depth) < o_.min_box_thickness || std::abs(depth) > o_.max_box_depth) continue;
      if (over * 2 < inl.size()) continue;
      if (std::abs(depth) >= std::abs(opposite_depth)) continue;
      const bool supported =
          bridge.empty() ? std::abs(depth) <= 2.0 * (seed.vmax - seed.vmin) : bridged(depth) >= 0.5;
      if (!supported) continue;
      opposite_depth = depth;
      opposite = static_cast<int>(k);
    }
    double c0 = 0.0, c1 = 0.0;
    if (opposite >= 0) {
      c0 = std::min(0.0, opposite_depth);
      c1 = std::max(0.0, opposite_depth);
    } else {
      // No opposite face: the depth is the contiguous run of the bridging faces' points, on
      // the side holding more of them.
      std::vector<double> below, above;
      for (double c : bridge) (c < 0.0 ? below : above).push_back(std::abs(c));
      auto run = [&](std::vector<double>& depths) {
        std::sort(depths.begin(), depths.end());
        double reach = 0.0;
        std::size_t count = 0;
        for (double d : depths) {
          if (d > reach + 3.0 * cell_) break;
          reach = std::max(reach, d);
          ++count;
        }
        return std::pair<double, std::size_t>(reach, count);
      };
      const auto [reach_below, n_below] = run(below);
      const auto [reach_above, n_above] = run(above);
      if (n_below >= n_above) {
        c0 = -reach_below;
      } else {
        c1 = reach_above;
      }
    }
    if (c1 - c0 < o_.min_box_thickness && o_.ground != nullptr &&
        std::abs(seed.n.z()) >= cos_tol_) {
      // A roof seen from above: down to the terrain under it.
      const Vec3 centre = seed.origin + 0.5 * (seed.umin + seed.umax) * seed.u +
                          0.5 * (seed.vmin + seed.vmax) * seed.v;
      const double radius =
          0.5 * std::hypot(seed.umax - seed.umin, seed.vmax - seed.vmin) + 2.0 * o_.ground->cell;
      const double g = o_.ground->lowest_near(centre.x(), centre.y(), radius);
      if (std::isfinite(g) && centre.z() - g >= o_.min_building_height) {
        const double c = (g - seed.origin.z()) * seed.n.z();
        c0 = std::min(0.0, c);
        c1 = std::max(0.0, c);
      }
    }
    if (c1 - c0 < o_.min_box_thickness) continue;
    // Extents: the seed's rectangle, widened by the opposite plane's.
    double u0 = seed.umin, u1 = seed.umax, v0 = seed.vmin, v1 = seed.vmax;
    if (opposite >= 0) {
      for (auto i : patches_[static_cast<std::size_t>(opposite)].members) {
        const Vec3 c = local(points_[i]);
        if (!inside_rect(c, margin)) continue;
        u0 = std::min(u0, c.x());
        u1 = std::max(u1, c.x());
        v0 = std::min(v0, c.y());
        v1 = std::max(v1, c.y());
      }
    }
    // Members: every plane point inside the box (grown by the margin); planes mostly inside
    // are used up.
    std::vector<std::uint32_t> members;
    for (auto& other : patches_) {
      if (other.used) continue;
      const auto& inl = other.members;
      std::size_t in = 0;
      for (auto i : inl) {
        if (used_[i]) continue;
        const Vec3 c = local(points_[i]);
        if (c.x() >= u0 - margin && c.x() <= u1 + margin && c.y() >= v0 - margin &&
            c.y() <= v1 + margin && c.z() >= c0 - margin && c.z() <= c1 + margin) {
          members.push_back(i);
          ++in;
        }
      }
      if (in * 10 >= inl.size() * 8) other.used = true;
    }
    seed.used = true;
    std::sort(members.begin(), members.end());
    const Eigen::Matrix3d rot = frame(seed.u, seed.v);
    const Vec3 corner = seed.origin + u0 * rot.col(0) + v0 * rot.col(1) + c0 * rot.col(2);
    auto loc = placement(rot, corner);
    if (!loc) continue;
    PrimitiveSpec spec;
    spec.type = PrimitiveType::Box;
    spec.size = Vec3(u1 - u0, v1 - v0, c1 - c0);
    spec.placement = *loc;
    const double area = 2.0 * (spec.size.x() * spec.size.y() + spec.size.y() * spec.size.z() +
                               spec.size.x() * spec.size.z());
    emit(std::move(spec), members, area, "box from plane " + std::to_string(seed.shape));
  }
  for (const auto& patch : patches_) {
    if (patch.used) continue;
    const auto& inl = patch.members;
    long long left = 0;
    for (auto i : inl) left += used_[i] ? 0 : 1;
    if (left == 0) continue;
    out_.rejected.push_back({"plane " + std::to_string(patch.shape),
                             patch.coverage < o_.min_seed_coverage
                                 ? "no box: points cover too little of its rectangle"
                                 : "no box: no parallel or orthogonal plane gives it a depth",
                             left});
  }
}

void Builder::curved(int index) {
  const DetectedShape& shape = shapes_.shapes[static_cast<std::size_t>(index)];
  const Surface& s = shape.surface;
  const std::string what = std::string(shape_type_name(s.type)) + " " + std::to_string(index);
  std::vector<std::uint32_t> members;
  for (auto i : shape.inliers) {
    if (!used_[i]) members.push_back(i);
  }
  if (static_cast<long long>(members.size()) < ransac_.min_points) {
    out_.rejected.push_back(
        {what, "inside an earlier primitive", static_cast<long long>(members.size())});
    return;
  }
  PrimitiveSpec spec;
  Vec3 e1, e2;
  detail::orthonormal_basis(s.axis, e1, e2);
  const Eigen::Matrix3d rot = frame(e1, e2);  // local z along the axis
  double t0 = INFINITY, t1 = -INFINITY;
  for (auto i : members) {
    const double t = (points_[i] - s.point).dot(s.axis);
    t0 = std::min(t0, t);
    t1 = std::max(t1, t);
  }
  if (s.type == ShapeType::Cylinder || s.type == ShapeType::Cone || s.type == ShapeType::Torus) {
    // Share of 10° sectors around the axis holding inliers.
    std::array<bool, 36> sector{};
    for (auto i : members) {
      const Vec3 d = points_[i] - s.point;
      const double phi = std::atan2(d.dot(e2), d.dot(e1));
      const auto k = static_cast<std::size_t>(
          std::clamp((phi + std::numbers::pi) / (2.0 * std::numbers::pi) * 36.0, 0.0, 35.0));
      sector[k] = true;
    }
    const double span = 10.0 * static_cast<double>(std::count(sector.begin(), sector.end(), true));
    if (span < o_.min_angular_span_deg) {
      out_.rejected.push_back(
          {what,
           "inliers span " + std::to_string(static_cast<int>(span)) + " degrees around the axis",
           static_cast<long long>(members.size())});
      return;
    }
    if (s.type != ShapeType::Torus && t1 - t0 < 2.0 * cell_) {
      out_.rejected.push_back({what, "shorter than two connectivity cells along the axis",
                               static_cast<long long>(members.size())});
      return;
    }
  }
  double area = 0.0;
  switch (s.type) {
    case ShapeType::Plane:
      return;
    case ShapeType::Cylinder: {
      spec.type = PrimitiveType::Cylinder;
      spec.radius = s.radius;
      spec.height = t1 - t0;
      auto loc = placement(rot, s.point + t0 * s.axis);
      if (!loc) return;
      spec.placement = *loc;
      area = 2.0 * std::numbers::pi * s.radius * spec.height;
      break;
    }
    case ShapeType::Cone: {
      // Radii where the inliers start and end along the axis, measured from the apex.
      t0 = std::max(t0, 0.0);
      spec.type = PrimitiveType::Cone;
      spec.radius = t0 * std::tan(s.angle);
      spec.radius2 = t1 * std::tan(s.angle);
      spec.height = t1 - t0;
      auto loc = placement(rot, s.point + t0 * s.axis);
      if (!loc) return;
      spec.placement = *loc;
      area = std::numbers::pi * (spec.radius + spec.radius2) * spec.height / std::cos(s.angle);
      break;
    }
    case ShapeType::Sphere: {
      spec.type = PrimitiveType::Sphere;
      spec.radius = s.radius;
      auto loc = placement(Eigen::Matrix3d::Identity(), s.point);
      if (!loc) return;
      spec.placement = *loc;
      area = 4.0 * std::numbers::pi * s.radius * s.radius;
      break;
    }
    case ShapeType::Torus: {
      spec.type = PrimitiveType::Torus;
      spec.radius = s.radius;
      spec.radius2 = s.radius2;
      auto loc = placement(rot, s.point);
      if (!loc) return;
      spec.placement = *loc;
      area = 4.0 * std::numbers::pi * std::numbers::pi * s.radius * s.radius2;
      break;
    }
  }
  emit(std::move(spec), members, area, what);
}

FittedPrimitives Builder::run() {
  if (o_.boxes) boxes();
  for (std::size_t s = 0; s < shapes_.shapes.size(); ++s) {
    const ShapeType type = shapes_.shapes[s].surface.type;
    if (type == ShapeType::Plane) {
      if (!o_.boxes) {
        out_.rejected.push_back({"plane " + std::to_string(s), "planes alone are not primitives",
                                 static_cast<long long>(shapes_.shapes[s].inliers.size())});
      }
      continue;
    }
    curved(static_cast<int>(s));
  }
  return std::move(out_);
}

}  // namespace

double GroundGrid::lowest_near(double x, double y, double radius) const {
  if (nx <= 0 || ny <= 0 || !(cell > 0.0)) return NAN;
  const auto clamp_x = [&](double v) {
    return std::clamp(static_cast<int>(std::floor((v - x0) / cell)), 0, nx - 1);
  };
  const auto clamp_y = [&](double v) {
    return std::clamp(static_cast<int>(std::floor((v - y0) / cell)), 0, ny - 1);
  };
  double best = NAN;
  for (int j = clamp_y(y - radius); j <= clamp_y(y + radius); ++j) {
    for (int i = clamp_x(x - radius); i <= clamp_x(x + radius); ++i) {
      const double h = z[static_cast<std::size_t>(j) * static_cast<std::size_t>(nx) +
                         static_cast<std::size_t>(i)];
      if (std::isfinite(h) && !(h >= best)) best = h;
    }
  }
  return best;
}

FittedPrimitives primitives_from_shapes(std::span<const Vec3> points,
                                        std::span<const Vec3> /*normals*/,
                                        const RansacResult& shapes, const PrimitiveOptions& options,
                                        const RansacOptions& ransac, int region) {
  Builder builder(points, shapes, options, ransac, region);
  return builder.run();
}

}  // namespace csgtile::geo
