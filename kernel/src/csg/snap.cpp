#include "csgtile/kernel/snap.h"

#include "snap_walls.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <set>
#include <tuple>

namespace csgtile::kernel {

namespace {

// The local axes of a primitive whose direction matters: all three of a box's, the axis (z)
// of the others; none for a sphere.
std::vector<int> snapped_axes(const PrimitiveSpec& p) {
  switch (p.type) {
    case PrimitiveType::Box:
      return {0, 1, 2};
    case PrimitiveType::Sphere:
      return {};
    default:
      return {2};
  }
}

// The local point a primitive turns about: the middle of its extent.
Vec3 local_centre(const PrimitiveSpec& p) {
  switch (p.type) {
    case PrimitiveType::Box:
      return 0.5 * p.size;
    case PrimitiveType::Cylinder:
    case PrimitiveType::Cone:
      return Vec3(0, 0, 0.5 * p.height);
    case PrimitiveType::Extrusion: {
      if (p.profile.empty()) return Vec3(0, 0, 0.5 * p.height);
      Vec2 lo = p.profile.front(), hi = lo;
      for (const Vec2& q : p.profile) {
        lo = lo.cwiseMin(q);
        hi = hi.cwiseMax(q);
      }
      const Vec2 mid = 0.5 * (lo + hi);
      return Vec3(mid.x(), mid.y(), 0.5 * p.height);
    }
    default:
      return Vec3::Zero();
  }
}

// The extent along local axis k whose two end faces are planes: a box's size, the height of a
// cylinder, cone or extrusion (base at local 0). Null for the others.
double* planar_extent(PrimitiveSpec& p, int k) {
  switch (p.type) {
    case PrimitiveType::Box:
      return &p.size[k];
    case PrimitiveType::Cylinder:
    case PrimitiveType::Cone:
    case PrimitiveType::Extrusion:
      return k == 2 ? &p.height : nullptr;
    default:
      return nullptr;
  }
}

// Whether the primitive is a surface of revolution about its local z axis through its local
// origin (its axis line is what step 5 snaps).
bool revolves(const PrimitiveSpec& p) {
  return p.type == PrimitiveType::Cylinder || p.type == PrimitiveType::Cone ||
         p.type == PrimitiveType::Torus || p.type == PrimitiveType::Revolution;
}

struct Direction {
  Vec3 sum = Vec3::Zero();
  Vec3 rep = Vec3::Zero();
  int count = 0;
};

// Axis k of primitive i lies along direction `cluster`, with `sign` (+1 or −1).
struct AxisUse {
  int cluster = -1;
  double sign = 1.0;
};

// A plane face of primitive `primitive` across its axis `axis` (direction `cluster`): its
// offset along `normal` (the primitive's own axis, turned the cluster's way), and the offset of
// the plane it snaps to (its own when none).
struct Face {
  int cluster, primitive, axis;
  Vec3 normal;
  double offset, to;
};

Eigen::Matrix3d orthonormal(const Vec3& x0, const Vec3& z0) {
  const Vec3 z = z0.normalized();
  const Vec3 x = (x0 - x0.dot(z) * z).normalized();
  Eigen::Matrix3d r;
  r.col(0) = x;
  r.col(1) = z.cross(x);
  r.col(2) = z;
  return r;
}

}  // namespace

Result<std::vector<PrimitiveSpec>> snap_primitives(const std::vector<PrimitiveSpec>& primitives,
                                                   const SnapOptions& options, SnapReport* report) {
  if (!(options.distance >= 0.0) || !std::isfinite(options.distance) || !(options.angle >= 0.0) ||
      !std::isfinite(options.angle)) {
    return Error{ErrorCode::InvalidArgument,
                 "snap: distance and angle must be finite and not negative"};
  }
  SnapReport local_counts;
  SnapReport& counts = report ? *report : local_counts;
  counts = SnapReport{};
  std::vector<PrimitiveSpec> out = primitives;
  const std::size_t n = out.size();

  // 1. Directions: each snapped axis joins the first direction whose running mean lies within
  // the angle, so a primitive may turn by up to about twice the angle (0.85° at 0.5° on the
  // fitted timber gate); faces move by at most the distance.
  const double cos_angle = std::cos(options.angle);
  std::vector<Direction> directions;
  std::vector<std::array<AxisUse, 3>> uses(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Matrix3d& r = out[i].placement.rotation();
    for (int k : snapped_axes(out[i])) {
      const Vec3 a = r.col(k);
      int found = -1;
      for (std::size_t c = 0; c < directions.size() && found < 0; ++c) {
        if (std::abs(a.dot(directions[c].rep)) >= cos_angle) found = static_cast<int>(c);
      }
      if (found < 0) {
        directions.push_back({a, a, 0});
        found = static_cast<int>(directions.size()) - 1;
      }
      Direction& d = directions[static_cast<std::size_t>(found)];
      const double sign = a.dot(d.rep) >= 0.0 ? 1.0 : -1.0;
      d.sum += sign * a;
      d.rep = d.sum.normalized();
      ++d.count;
      uses[i][static_cast<std::size_t>(k)] = {found, sign};
    }
  }
  // A direction within the angle of the vertical is the vertical (models are georeferenced
  // with z up: columns, walls and floors are meant plumb and level). Directions within the
  // angle of a right angle to a more used one (the vertical first) become orthogonal to it.
  std::vector<bool> vertical(directions.size(), false);
  for (std::size_t c = 0; c < directions.size(); ++c) {
    Vec3& d = directions[c].rep;
    if (std::abs(d.z()) >= cos_angle) {
      d = Vec3(0, 0, d.z() > 0 ? 1.0 : -1.0);
      vertical[c] = true;
    }
  }
  std::vector<std::size_t> order(directions.size());
  for (std::size_t c = 0; c < order.size(); ++c) order[c] = c;
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    if (vertical[a] != vertical[b]) return static_cast<bool>(vertical[a]);
    return directions[a].count > directions[b].count;
  });
  const double sin_angle = std::sin(options.angle);
  for (std::size_t oi = 0; oi < order.size(); ++oi) {
    Vec3& d = directions[order[oi]].rep;
    for (std::size_t oj = 0; oj < oi; ++oj) {
      const Vec3& e = directions[order[oj]].rep;
      if (std::abs(d.dot(e)) <= sin_angle) d = (d - d.dot(e) * e).normalized();
    }
  }
  counts.directions = static_cast<int>(directions.size());

  // 2. Each primitive turned about its centre onto its axes' directions.
  for (std::size_t i = 0; i < n; ++i) {
    PrimitiveSpec& p = out[i];
    const std::vector<int> axes = snapped_axes(p);
    if (axes.empty()) continue;
    const Location& at = p.placement;
    const Eigen::Matrix3d& r = at.rotation();
    auto target = [&](int k) {
      const AxisUse& u = uses[i][static_cast<std::size_t>(k)];
      return Vec3(u.sign * directions[static_cast<std::size_t>(u.cluster)].rep);
    };
    // z onto its direction exactly; x as near as it can stay (a box's: onto its own).
    const Eigen::Matrix3d turned =
        orthonormal(axes.size() == 3 ? target(0) : Vec3(r.col(0)), target(2));
    if (turned == r) continue;
    const double turn = Eigen::AngleAxisd(turned * r.transpose()).angle();
    if (turn == 0.0) continue;
    counts.max_turn = std::max(counts.max_turn, turn);
    for (int k : axes) {
      if ((turned.col(k) - r.col(k)).norm() > 0.0) ++counts.axes_snapped;
    }
    const Vec3 c = local_centre(p);
    const Vec3 centre = at.apply_point(c);
    const Vec3 t = centre - at.scale() * (turned * c);
    auto moved = Location::from_parts(turned, at.scale(), t);
    if (!moved.ok()) return moved.error();
    // Clip planes stay where they are in the world.
    for (Eigen::Vector4d& clip : p.clips) {
      const Vec3 normal = r * clip.head<3>();
      const double world_d = at.scale() * clip.w() + normal.dot(at.translation());
      clip.head<3>() = turned.transpose() * normal;
      clip.w() = (world_d - normal.dot(t)) / at.scale();
    }
    p.placement = moved.value();
  }

  // 3. Plane faces along each direction, in pairs (low end, high end) per primitive axis:
  // offsets within the distance become one plane.
  std::vector<Face> faces;
  for (std::size_t i = 0; i < n; ++i) {
    PrimitiveSpec& p = out[i];
    for (int k : snapped_axes(p)) {
      const double* extent = planar_extent(p, k);
      if (!extent) continue;
      const AxisUse& u = uses[i][static_cast<std::size_t>(k)];
      const Vec3 dir = u.sign * p.placement.rotation().col(k);
      const double low = dir.dot(p.placement.translation());
      const double high = low + u.sign * p.placement.scale() * *extent;
      faces.push_back({u.cluster, static_cast<int>(i), k, dir, low, low});
      faces.push_back({u.cluster, static_cast<int>(i), k, dir, high, high});
    }
  }
  std::vector<std::size_t> by_offset(faces.size());
  for (std::size_t f = 0; f < by_offset.size(); ++f) by_offset[f] = f;
  std::stable_sort(by_offset.begin(), by_offset.end(), [&](std::size_t a, std::size_t b) {
    return std::tie(faces[a].cluster, faces[a].offset) <
           std::tie(faces[b].cluster, faces[b].offset);
  });
  for (std::size_t g = 0; g < by_offset.size();) {
    const Face& first = faces[by_offset[g]];
    std::size_t end = g + 1;
    std::set<std::pair<int, int>> members{{first.primitive, first.axis}};
    while (end < by_offset.size()) {
      const Face& next = faces[by_offset[end]];
      if (next.cluster != first.cluster || next.offset - first.offset > options.distance ||
          !members.insert({next.primitive, next.axis}).second)
        break;
      ++end;
    }
    if (end - g >= 2) {
      double mean = 0.0;
      for (std::size_t f = g; f < end; ++f) mean += faces[by_offset[f]].offset;
      mean /= static_cast<double>(end - g);
      ++counts.planes;
      for (std::size_t f = g; f < end; ++f) faces[by_offset[f]].to = mean;
    }
    g = end;
  }

  // 4. Each primitive's faces moved: its extent along the axis and its position.
  std::vector<Vec3> shift(n, Vec3::Zero());
  for (std::size_t f = 0; f < faces.size(); f += 2) {
    const Face& low = faces[f];
    const Face& high = faces[f + 1];
    if (low.to == low.offset && high.to == high.offset) continue;
    const auto i = static_cast<std::size_t>(low.primitive);
    PrimitiveSpec& p = out[i];
    double* extent = planar_extent(p, low.axis);
    const AxisUse& u = uses[i][static_cast<std::size_t>(low.axis)];
    const double new_extent = u.sign * (high.to - low.to) / p.placement.scale();
    if (!(new_extent > 0.5 * *extent)) continue;  // a thin primitive keeps its faces
    *extent = new_extent;
    shift[i] += (low.to - low.offset) * low.normal;
    for (const Face* face : {&low, &high}) {
      if (face->to == face->offset) continue;
      ++counts.faces_snapped;
      counts.max_move = std::max(counts.max_move, std::abs(face->to - face->offset));
    }
  }
  // 5. Axes of revolution (cylinders, cones, tori, revolutions) along one direction whose
  // lines lie within the distance of each other become one line (their mean), and cylinders
  // on one line whose radii differ by at most the distance one radius: a column fitted in two
  // pieces is one column, not two surfaces micrometres apart crossing at grazing angles.
  struct Line {
    int cluster;
    Vec3 sum = Vec3::Zero(), rep = Vec3::Zero();
    std::vector<std::size_t> members;
  };
  std::vector<Line> lines;
  std::vector<Vec3> across(n, Vec3::Zero());  // each primitive's axis point ⟂ its direction
  for (std::size_t i = 0; i < n; ++i) {
    if (!revolves(out[i])) continue;
    const AxisUse& u = uses[i][2];
    const Vec3& dir = directions[static_cast<std::size_t>(u.cluster)].rep;
    const Vec3 q = out[i].placement.translation() + shift[i];
    across[i] = q - q.dot(dir) * dir;
    Line* line = nullptr;
    for (Line& l : lines) {
      if (!line && l.cluster == u.cluster && (l.rep - across[i]).norm() <= options.distance)
        line = &l;
    }
    if (!line) line = &lines.emplace_back(Line{u.cluster, Vec3::Zero(), Vec3::Zero(), {}});
    line->members.push_back(i);
    line->sum += across[i];
    line->rep = line->sum / static_cast<double>(line->members.size());
  }
  for (const Line& l : lines) {
    if (l.members.size() < 2) continue;
    ++counts.lines;
    for (std::size_t i : l.members) {
      const Vec3 move = l.rep - across[i];
      if (move.isZero(0.0)) continue;
      shift[i] += move;
      ++counts.axes_moved;
      counts.max_move = std::max(counts.max_move, move.norm());
    }
    // Radii of its cylinders, in groups within the distance (sorted), each group its mean.
    std::vector<std::size_t> cylinders;
    for (std::size_t i : l.members) {
      if (out[i].type == PrimitiveType::Cylinder) cylinders.push_back(i);
    }
    auto world_radius = [&](std::size_t i) { return out[i].radius * out[i].placement.scale(); };
    std::stable_sort(cylinders.begin(), cylinders.end(), [&](std::size_t a, std::size_t b) {
      return world_radius(a) < world_radius(b);
    });
    for (std::size_t g = 0; g < cylinders.size();) {
      std::size_t end = g + 1;
      while (end < cylinders.size() &&
             world_radius(cylinders[end]) - world_radius(cylinders[g]) <= options.distance)
        ++end;
      if (end - g >= 2) {
        double mean = 0.0;
        for (std::size_t k = g; k < end; ++k) mean += world_radius(cylinders[k]);
        mean /= static_cast<double>(end - g);
        for (std::size_t k = g; k < end; ++k) {
          PrimitiveSpec& c = out[cylinders[k]];
          const double moved = std::abs(mean - world_radius(cylinders[k]));
          if (moved == 0.0) continue;
          ++counts.radii_snapped;
          counts.max_move = std::max(counts.max_move, moved);
          c.radius = mean / c.placement.scale();
        }
      }
      g = end;
    }
  }

  for (std::size_t i = 0; i < n; ++i) {
    if (shift[i].isZero(0.0)) continue;
    PrimitiveSpec& p = out[i];
    const Location& at = p.placement;
    for (Eigen::Vector4d& clip : p.clips) {
      const Vec3 normal = at.rotation() * clip.head<3>();
      clip.w() -= normal.dot(shift[i]) / at.scale();
    }
    auto moved = Location::from_parts(at.rotation(), at.scale(), at.translation() + shift[i]);
    if (!moved.ok()) return moved.error();
    p.placement = moved.value();
  }
  // 6. Side walls of parallel extrusions share their vertices (snap_walls.h).
  detail::share_extrusion_walls(out, options.distance, counts);
  return out;
}

}  // namespace csgtile::kernel
