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
#include "csgtile/kernel/mass_properties.h"
#include "fit_internal.h"
#include "plane2d.h"
#include "synth/ray_internal.h"

namespace csgtile::fit {

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
  double sagitta = 0.0;  // how far its points bow out of the plane across its width
  bool used = false;
};

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
  // The smallest rectangle around the points has a side along an edge of their hull.
  const auto rectangle = detail::smallest_rectangle(detail::convex_hull(flat), 1e-12);
  const Vec2 best_dir = rectangle ? rectangle->dir : Vec2(1, 0);
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
  // A strip of a column that the RANSAC took for a plane bows across its width: fit the
  // offset from the plane as a parabola of the across coordinate (c = α + β·b + γ·b²) and
  // keep how far it bows over the half-width, γ·(w/2)².
  Eigen::Matrix3d normal_matrix = Eigen::Matrix3d::Zero();
  Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
  const double mid = 0.5 * (patch.vmin + patch.vmax);
  for (auto i : patch.members) {
    const Vec3 d = points[i] - patch.origin;
    const double b = d.dot(patch.v) - mid;
    const Eigen::Vector3d row(1.0, b, b * b);
    normal_matrix += row * row.transpose();
    rhs += row * d.dot(patch.n);
  }
  if (patch.members.size() >= 6) {
    const Eigen::Vector3d coef = normal_matrix.ldlt().solve(rhs);
    const double half = 0.5 * (patch.vmax - patch.vmin);
    if (std::isfinite(coef.z())) patch.sagitta = std::abs(coef.z()) * half * half;
  }
  return patch;
}

// The noise of the points about a plane patch: 1.4826 × the median |offset| of the points
// over the middle 80% of its rectangle within 0.25 m of it, a robust σ that edge
// points of walls and the points of anything standing on it barely move. 0 for fewer than
// 8 points.
double robust_noise(std::span<const Vec3> points, const PlanePatch& seed) {
  const double du = 0.1 * (seed.umax - seed.umin), dv = 0.1 * (seed.vmax - seed.vmin);
  std::vector<double> offsets;
  for (const Vec3& p : points) {
    if (!p.allFinite()) continue;
    const Vec3 d = p - seed.origin;
    const double a = d.dot(seed.u), b = d.dot(seed.v), c = std::abs(d.dot(seed.n));
    if (a < seed.umin + du || a > seed.umax - du || b < seed.vmin + dv || b > seed.vmax - dv ||
        c > 0.25) {
      continue;
    }
    offsets.push_back(c);
  }
  if (offsets.size() < 8) return 0.0;
  const auto mid = offsets.begin() + static_cast<std::ptrdiff_t>(offsets.size() / 2);
  std::nth_element(offsets.begin(), mid, offsets.end());
  return 1.4826 * *mid;
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
  Builder(std::span<const Vec3> points, std::span<const Vec3> normals, const RansacResult& shapes,
          const PrimitiveOptions& o, const RansacOptions& ransac, int region)
      : points_(points),
        normals_(normals),
        shapes_(shapes),
        o_(o),
        ransac_(ransac),
        region_(region),
        used_(points.size(), 0) {
    cos_tol_ = std::cos(o.angle_tolerance_deg * std::numbers::pi / 180.0);
    cell_ = shapes.cluster_epsilon > 0.0 ? shapes.cluster_epsilon : 3.0 * ransac.epsilon;
    for (const Vec3& p : points) {
      if (p.allFinite()) region_box_.add(p);
    }
    // A footprint is evidence too: a building reaches over all of it, points or not.
    if (o.footprint != nullptr && !region_box_.empty()) {
      for (const auto& polygon : *o.footprint) {
        for (const kernel::Vec2& q : polygon.outer) {
          region_box_.add(Vec3(q.x(), q.y(), region_box_.min.z()));
        }
      }
    }
  }

  FittedPrimitives run();

 private:
  // How far a box reaches behind (c0 < 0) or before (c1 > 0) its seed plane, and the extent
  // across (v) of the opposite face when one was seen.
  struct Depth {
    double c0 = 0.0, c1 = 0.0;
    double v0 = INFINITY, v1 = -INFINITY;
  };
  // Which axis of the seed's frame a point's normal follows.
  enum class Facing : std::uint8_t { Normal, Across, Along, Other };
  struct Framed {
    double a = 0.0, b = 0.0, c = 0.0;  // along u, v, n of the seed
    Facing facing = Facing::Other;
  };
  std::vector<Framed> framed_near(const PlanePatch& seed, double across, double cos_normal) const;
  Depth box_depth(const PlanePatch& seed, double margin, double cos_normal) const;
  std::pair<double, double> box_length(const PlanePatch& seed, double c0, double c1, double v0,
                                       double v1, double tight, double cos_normal) const;
  bool round_section(const std::vector<std::uint32_t>& members, const PlanePatch& seed,
                     const std::array<double, 4>& section) const;
  void boxes();
  void curved(int index);
  void blocks();
  // What the proposal steps see of the region (points, shapes, what is used or absorbed).
  detail::ProposalInput proposal_input() const {
    detail::ProposalInput in;
    in.points = points_;
    in.normals = normals_;
    in.shapes = &shapes_;
    in.used = &used_;
    in.absorbed = &absorbed_;
    in.options = &o_;
    in.ransac = &ransac_;
    in.cell = cell_;
    return in;
  }
  std::string coaxial_overlap(const PrimitiveSpec& spec) const;
  bool take(const detail::Proposal& proposal);
  void emit(PrimitiveSpec spec, const std::vector<std::uint32_t>& members, double area,
            const std::string& what);

  std::span<const Vec3> points_;
  std::span<const Vec3> normals_;
  const RansacResult& shapes_;
  PrimitiveOptions o_;
  RansacOptions ransac_;
  int region_;
  double cos_tol_ = 1.0;
  double cell_ = 0.1;
  std::vector<char> used_;
  std::vector<char> absorbed_;  // per shape: part of a kept extrusion or revolution
  std::vector<PlanePatch> patches_;
  kernel::BoundingBox region_box_;  // of the region's finite points
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
  const double coverage = coverage_of(points_, members, cell_, area);
  if (std::string why = detail::unsupported(spec, kernel::bounding_box(solid.value()), coverage,
                                            region_box_, cell_, o_);
      !why.empty()) {
    out_.rejected.push_back({what, std::move(why), static_cast<long long>(members.size())});
    return;
  }
  geo::ScenePrimitive p;
  p.spec = std::move(spec);
  p.id = "r" + std::to_string(region_) + "-" + std::to_string(out_.primitives.size());
  geo::FitQuality q;
  q.inliers = static_cast<long long>(members.size());
  // The RMS distance of its points to its solid (the model), on a mesh finer than the fit's
  // tolerance; when that cannot be measured, to the surfaces their RANSAC shapes found.
  const double chordal = std::clamp(0.25 * ransac_.epsilon, 0.001, 0.05);
  if (const auto rms = detail::boundary_rms(solid.value(), points_, members, chordal)) {
    q.rms = *rms;
  } else {
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
  }
  q.coverage = coverage;
  p.quality = q;
  ++out_.per_type[static_cast<std::size_t>(p.spec.type)];
  out_.assigned_points += q.inliers;
  for (auto i : members) used_[i] = 1;
  out_.primitives.push_back(std::move(p));
}

// The unused points over the seed's rectangle (grown by `across` on its long edges) within
// max_box_depth of it, in its frame, with the axis their normals follow.
std::vector<Builder::Framed> Builder::framed_near(const PlanePatch& seed, double across,
                                                  double cos_normal) const {
  std::vector<Framed> near;
  for (std::size_t i = 0; i < points_.size(); ++i) {
    if (used_[i] || !points_[i].allFinite()) continue;
    const Vec3 d = points_[i] - seed.origin;
    Framed f;
    f.a = d.dot(seed.u);
    f.b = d.dot(seed.v);
    f.c = d.dot(seed.n);
    if (f.a < seed.umin || f.a > seed.umax || f.b < seed.vmin - across ||
        f.b > seed.vmax + across || std::abs(f.c) > o_.max_box_depth) {
      continue;
    }
    const Vec3& n = normals_.empty() ? Vec3::Zero() : normals_[i];
    if (std::abs(n.dot(seed.n)) >= cos_normal) {
      f.facing = Facing::Normal;
    } else if (std::abs(n.dot(seed.v)) >= cos_normal) {
      f.facing = Facing::Across;
    } else if (std::abs(n.dot(seed.u)) >= cos_normal) {
      f.facing = Facing::Along;
    }
    near.push_back(f);
  }
  return near;
}

// The depth of the box behind or before a seed face, from the region's points rather than
// from detected planes: a beam's far side or underside is often too sparse (a few dozen
// points at a grazing angle) or too merged with its neighbours' (one plane under a whole
// grid of beams) to be a plane of its own, but its points still say where the box ends.
// On each side of the seed, within the middle of its length (its ends may touch crossing
// members):
//  - the opposite face: the nearest depth at which points facing like the seed gather, spread
//    over a good part of the length;
//  - the bridging faces: points facing across the seed (normal along v) on its long edges,
//    whose contiguous run of depths from the seed says how deep the box reaches.
// An opposite face counts when the bridging faces span half the gap to it, or, when none is
// seen, when it is no farther than twice the seed's width. The side with more evidence wins.
Builder::Depth Builder::box_depth(const PlanePatch& seed, double margin, double cos_normal) const {
  const auto near = framed_near(seed, margin, cos_normal);
  double inner0 = seed.umin + margin, inner1 = seed.umax - margin;
  if (inner1 - inner0 < 0.5 * (seed.umax - seed.umin)) {
    inner0 = seed.umin + 0.25 * (seed.umax - seed.umin);
    inner1 = seed.umax - 0.25 * (seed.umax - seed.umin);
  }
  const double width = seed.vmax - seed.vmin;
  const double window = 2.0 * ransac_.epsilon;
  constexpr std::size_t kMinFacePoints = 8;
  Depth best;
  std::size_t best_score = 0;
  for (const double side : {-1.0, 1.0}) {
    std::vector<double> bridge;
    std::vector<std::pair<double, std::size_t>> parallel;  // depth, index into near
    for (std::size_t k = 0; k < near.size(); ++k) {
      const Framed& f = near[k];
      const double d = side * f.c;
      if (d <= 0.0 || f.a < inner0 || f.a > inner1) continue;
      if (f.facing == Facing::Across &&
          (std::abs(f.b - seed.vmin) <= margin || std::abs(f.b - seed.vmax) <= margin)) {
        bridge.push_back(d);
      } else if (f.facing == Facing::Normal && d > window) {
        parallel.emplace_back(d, k);
      }
    }
    // Contiguous run of bridging depths from the seed.
    std::sort(bridge.begin(), bridge.end());
    double reach = 0.0;
    std::size_t bridged = 0;
    for (double d : bridge) {
      if (d > reach + 3.0 * cell_) break;
      reach = std::max(reach, d);
      ++bridged;
    }
    if (bridged < kMinFacePoints) {
      reach = 0.0;
      bridged = 0;
    }
    // The nearest opposite face: a window of depths holding enough points spread along the
    // seed's length.
    std::sort(parallel.begin(), parallel.end());
    double opposite = 0.0, opposite_v0 = INFINITY, opposite_v1 = -INFINITY;
    std::size_t opposite_count = 0;
    for (std::size_t j = 0, e = 0; j < parallel.size(); ++j) {
      e = std::max(e, j);
      while (e + 1 < parallel.size() && parallel[e + 1].first <= parallel[j].first + window) ++e;
      const std::size_t count = e - j + 1;
      if (count < kMinFacePoints) continue;
      double a0 = INFINITY, a1 = -INFINITY, sum = 0.0, b0 = INFINITY, b1 = -INFINITY;
      for (std::size_t k = j; k <= e; ++k) {
        const Framed& f = near[parallel[k].second];
        a0 = std::min(a0, f.a);
        a1 = std::max(a1, f.a);
        b0 = std::min(b0, f.b);
        b1 = std::max(b1, f.b);
        sum += parallel[k].first;
      }
      if (a1 - a0 < 0.3 * (inner1 - inner0)) continue;
      opposite = sum / static_cast<double>(count);
      opposite_count = count;
      opposite_v0 = b0;
      opposite_v1 = b1;
      break;
    }
    double depth = reach;
    std::size_t score = bridged;
    bool has_opposite = false;
    if (opposite_count > 0 && opposite >= o_.min_box_thickness) {
      const bool supported =
          bridged > 0 ? reach >= 0.5 * opposite - margin : opposite <= 2.0 * width;
      if (supported) {
        depth = opposite;
        score += opposite_count;
        has_opposite = true;
      }
    }
    if (depth < o_.min_box_thickness || score <= best_score) continue;
    best_score = score;
    best = Depth{};
    if (side < 0.0) {
      best.c0 = -depth;
    } else {
      best.c1 = depth;
    }
    if (has_opposite) {
      best.v0 = opposite_v0;
      best.v1 = opposite_v1;
    }
  }
  return best;
}

// The box's extent along the seed's length: from the seed's rectangle, grown at each end over
// the points of the box's faces within its cross-section (long faces, and the edges between
// them where normals straddle), so that a face shortened by a shadow or split by the RANSAC
// is completed by the other faces' points; a sparse face's normals straddle its edges, so a
// point on the section's outline counts whichever face its normal follows, as long as the
// normal lies in the section's plane. Points facing along the length (normal more than
// 30° out of the section's plane) end it: inside the section, an end face or a member the
// box runs into; just beside it (within the noise margin), a crossing member or a column at
// a junction, after which only half the usual gap is crossed. Points of a box built earlier
// within the section (a crossing member's) count as such a crossing; points of a curved
// surface across the length (a column) are not faces of the box. Over gaps with nothing
// facing along, the faces go on for up to twice the section's larger side (shadows).
std::pair<double, double> Builder::box_length(const PlanePatch& seed, double c0, double c1,
                                              double v0, double v1, double tight,
                                              double cos_normal) const {
  const double length = seed.umax - seed.umin;
  constexpr double kAlong = 0.5;  // |normal · u| of a point facing along the length
  enum class Seen : std::uint8_t { Face, End, Beside };
  std::vector<std::pair<double, Seen>> beyond_low, beyond_high;  // distance past the seed
  std::size_t within = 0;  // face points along the seed's own length
  for (std::size_t i = 0; i < points_.size(); ++i) {
    if (!points_[i].allFinite() || normals_.empty()) continue;
    const Vec3 d = points_[i] - seed.origin;
    const double a = d.dot(seed.u), b = d.dot(seed.v), c = d.dot(seed.n);
    if (a < seed.umin - 3.0 * length || a > seed.umax + 3.0 * length) continue;
    if (b < v0 - tight || b > v1 + tight || c < c0 - tight || c > c1 + tight) continue;
    if (used_[i]) {
      // A member built earlier (a crossing beam) holds this point: the box meets it here.
      if (a < seed.umin) beyond_low.emplace_back(seed.umin - a, Seen::Beside);
      if (a > seed.umax) beyond_high.emplace_back(a - seed.umax, Seen::Beside);
      continue;
    }
    const Vec3& n = normals_[i];
    if (n.squaredNorm() < 0.5) continue;
    const bool along = std::abs(n.dot(seed.u)) >= kAlong;
    // A curved surface across the length (a column the box passes or meets) is a member
    // crossing it, not one of its faces, whichever way its points' normals turn.
    const int shape = shapes_.assignment.empty() ? -1 : shapes_.assignment[i];
    if (!along && shape >= 0 &&
        shapes_.shapes[static_cast<std::size_t>(shape)].surface.type != ShapeType::Plane &&
        std::abs(shapes_.shapes[static_cast<std::size_t>(shape)].surface.axis.dot(seed.u)) <
            kAlong) {
      continue;
    }
    const bool near_c = std::abs(c - c0) <= tight || std::abs(c - c1) <= tight;
    const bool near_b = std::abs(b - v0) <= tight || std::abs(b - v1) <= tight;
    const bool on_face = (near_c && b >= v0 && b <= v1 && std::abs(n.dot(seed.n)) >= cos_normal) ||
                         (near_b && c >= c0 && c <= c1 && std::abs(n.dot(seed.v)) >= cos_normal) ||
                         ((near_b || near_c) && !along);
    Seen seen = Seen::Face;
    if (along) {
      const bool inside = b >= v0 + tight && b <= v1 - tight && c >= c0 + tight && c <= c1 - tight;
      seen = inside ? Seen::End : Seen::Beside;
    } else if (!on_face) {
      continue;  // near the box but on none of its faces: says nothing
    }
    if (a >= seed.umin && a <= seed.umax) {
      within += seen == Seen::Face ? 1 : 0;
    } else if (a < seed.umin) {
      beyond_low.emplace_back(seed.umin - a, seen);
    } else {
      beyond_high.emplace_back(a - seed.umax, seen);
    }
  }
  // Face points follow each other within a few times their mean distance along the seed
  // (its own density: a sparse beam is not the dense column beside it).
  const double mean_gap = length / static_cast<double>(std::max<std::size_t>(within, 1));
  const double max_gap = std::max(8.0 * mean_gap, 2.0 * ransac_.epsilon);
  // A shadow (an obstacle between the scanner and the face) leaves a gap of about the
  // obstacle's size; where the same section continues beyond it with nothing facing along
  // the length in between, the face goes on: gaps up to twice the section's larger side.
  const double shadow_gap = std::max(max_gap, 2.0 * std::max(v1 - v0, c1 - c0));
  auto grow = [&](std::vector<std::pair<double, Seen>>& beyond) {
    std::sort(beyond.begin(), beyond.end());
    constexpr int kEnding = 3;  // a few straddling normals mix in with a face's last points
    double reach = 0.0;
    int ends = 0;
    bool beside = false;  // something beside the section faced along since the last face point
    for (const auto& [distance, seen] : beyond) {
      if (seen == Seen::End) {
        if (++ends >= kEnding) break;
        beside = true;
        continue;
      }
      if (seen == Seen::Beside) {
        beside = true;
        continue;
      }
      if (distance - reach > (beside ? 0.5 * max_gap : shadow_gap)) break;
      reach = distance;
      ends = 0;
      beside = false;
    }
    return reach;
  };
  const double lo = grow(beyond_low), hi = grow(beyond_high);
  return {seed.umin - lo, seed.umax + hi};
}

// Model selection between a box and a cylinder along its length: the members' distances to
// the box's section (a rectangle, v0..v1 × c0..c1 in the seed's frame) against their
// distances to the circle fitted to them in that plane (algebraic least squares). A strip of
// a column that the RANSAC took for a plane, with the column's curve beside it as "depth",
// is round: the circle fits it clearly better than the rectangle, and the box is refused so
// that the points stay for the cylinder.
bool Builder::round_section(const std::vector<std::uint32_t>& members, const PlanePatch& seed,
                            const std::array<double, 4>& section) const {
  if (members.size() < 8) return false;
  const auto [v0, v1, c0, c1] = section;
  std::vector<Vec2> flat;
  flat.reserve(members.size());
  double box_sum = 0.0;
  const Vec2 mid(0.5 * (v0 + v1), 0.5 * (c0 + c1));
  for (auto i : members) {
    const Vec3 d = points_[i] - seed.origin;
    const Vec2 q(d.dot(seed.v) - mid.x(), d.dot(seed.n) - mid.y());
    flat.push_back(q);
    const double hx = 0.5 * (v1 - v0), hy = 0.5 * (c1 - c0);
    const double ox = std::abs(q.x()) - hx, oy = std::abs(q.y()) - hy;
    const double e = (ox > 0.0 || oy > 0.0) ? std::hypot(std::max(ox, 0.0), std::max(oy, 0.0))
                                            : std::min(-ox, -oy);
    box_sum += e * e;
  }
  const auto circle = detail::fit_circle(flat);
  if (!circle) return false;
  if (circle->radius > ransac_.max_radius) return false;
  double circle_sum = 0.0;
  for (const auto& q : flat) {
    const double e = (q - circle->centre).norm() - circle->radius;
    circle_sum += e * e;
  }
  // Clearly better: the circle's error well under the rectangle's and well within epsilon (a
  // beam seen on two sides is an L that a circle follows only loosely).
  const double n = static_cast<double>(members.size());
  const double circle_rms = std::sqrt(circle_sum / n), box_rms = std::sqrt(box_sum / n);
  return circle_rms < 0.75 * box_rms && circle_rms <= 0.6 * ransac_.epsilon;
}

void Builder::boxes() {
  std::vector<int> order;
  for (std::size_t s = 0; s < shapes_.shapes.size(); ++s) {
    if (shapes_.shapes[s].surface.type != ShapeType::Plane || absorbed_[s]) continue;
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
  // Points belong to a box face within this distance of it (noise, not connectivity).
  const double tight = 2.0 * ransac_.epsilon;
  const double cos_normal = std::cos(ransac_.normal_deviation_deg * std::numbers::pi / 180.0);
  for (int seed_index : order) {
    PlanePatch& seed = patches_[static_cast<std::size_t>(seed_index)];
    if (seed.used || seed.coverage < o_.min_seed_coverage) continue;
    if (seed.sagitta > 0.5 * ransac_.epsilon) continue;
    const Depth depth = box_depth(seed, margin, cos_normal);
    double c0 = depth.c0, c1 = depth.c1;
    // A roof's own noise band (a few stray points below or above it) is no depth: judged
    // against the plane's noise (robust σ of the points over it) and epsilon, not only the
    // thinnest box. The noise (a pass over the region) is measured only for horizontal seeds
    // wide enough to be a roof, with a terrain to reach.
    const auto no_own_depth = [&] {
      const double least = std::max(o_.min_box_thickness, 3.0 * ransac_.epsilon);
      return c1 - c0 < least || c1 - c0 < 4.0 * robust_noise(points_, seed);
    };
    if (o_.ground != nullptr && std::abs(seed.n.z()) >= cos_tol_ &&
        std::min(seed.umax - seed.umin, seed.vmax - seed.vmin) >= o_.min_building_width &&
        no_own_depth()) {
      // A roof seen from above: down to the terrain under it. Only for roofs wide enough to
      // be a building: a beam's underside seen from below has no depth of its own either.
      const Vec3 centre = seed.origin + 0.5 * (seed.umin + seed.umax) * seed.u +
                          0.5 * (seed.vmin + seed.vmax) * seed.v;
      const double radius =
          0.5 * std::hypot(seed.umax - seed.umin, seed.vmax - seed.vmin) + 2.0 * o_.ground->cell;
      // The lowest terrain around the roof's footprint (not farther off), else near it.
      std::vector<Vec2> corners;
      for (const double a : {seed.umin, seed.umax}) {
        for (const double b : {seed.vmin, seed.vmax}) {
          const Vec3 w = seed.origin + a * seed.u + b * seed.v;
          corners.emplace_back(w.x(), w.y());
        }
      }
      double g = detail::lowest_ground_under(*o_.ground, detail::convex_hull(corners));
      if (!std::isfinite(g)) g = o_.ground->lowest_near(centre.x(), centre.y(), radius);
      if (std::isfinite(g) && centre.z() - g >= o_.min_building_height) {
        const double c = (g - seed.origin.z()) * seed.n.z();
        c0 = std::min(0.0, c);
        c1 = std::max(0.0, c);
      }
    }
    if (c1 - c0 < o_.min_box_thickness) continue;
    // Extents: the seed's rectangle, widened across by the opposite face's points and along
    // its length over the points of the box's long faces (a face partly shadowed by an
    // obstacle in front of it, or cut by a column, is completed by the others).
    double v0 = std::min(seed.vmin, depth.v0), v1 = std::max(seed.vmax, depth.v1);
    // Plain variables, not a structured binding: lambdas below capture them (clang 14 does
    // not capture bindings).
    const std::pair<double, double> length = box_length(seed, c0, c1, v0, v1, tight, cos_normal);
    const double u0 = length.first, u1 = length.second;
    // Never below the terrain: a depth that crosses a pitched roof or a building to points on
    // its far side can put a tilted box metres into the ground. The side of the box away from
    // the seed is clipped at the lowest ground near it; a seed face itself under the terrain,
    // or nothing left after clipping, gives no box.
    if (o_.ground != nullptr) {
      std::vector<Vec2> corners;  // the box's footprint: its corners seen from above
      for (const double a : {u0, u1}) {
        for (const double b : {v0, v1}) {
          for (const double c : {c0, c1}) {
            const Vec3 w = seed.origin + a * seed.u + b * seed.v + c * seed.n;
            corners.emplace_back(w.x(), w.y());
          }
        }
      }
      const double g = detail::lowest_ground_under(*o_.ground, detail::convex_hull(corners));
      const double tolerance = std::max(0.2, 2.0 * ransac_.epsilon);
      double face = INFINITY;  // lowest corner of the box's face on the seed plane
      for (const double a : {u0, u1}) {
        for (const double b : {v0, v1}) {
          face = std::min(face, (seed.origin + a * seed.u + b * seed.v).z());
        }
      }
      const double nz = seed.n.z();
      if (std::isfinite(g) && face + std::min(c0 * nz, c1 * nz) < g - tolerance) {
        if (nz > 0.0) {
          c0 = std::max(c0, std::min(0.0, (g - face) / nz));
        } else if (nz < 0.0) {
          c1 = std::min(c1, std::max(0.0, (g - face) / nz));
        }
        if (face < g - tolerance || c1 - c0 < o_.min_box_thickness) {
          out_.rejected.push_back({"box from plane " + std::to_string(seed.shape),
                                   "it would reach below the terrain",
                                   static_cast<long long>(seed.members.size())});
          seed.used = true;
          continue;
        }
      }
    }
    auto local = [&](const Vec3& p) {
      const Vec3 d = p - seed.origin;
      return Vec3(d.dot(seed.u), d.dot(seed.v), d.dot(seed.n));
    };
    // Members: every unused point inside the box (grown by the noise margin), whatever
    // surface the RANSAC gave it (edges of a beam are sometimes thin cylinders); planes
    // mostly inside are used up.
    std::vector<std::uint32_t> members;
    auto inside_box = [&](const Vec3& c) {
      return c.x() >= u0 - tight && c.x() <= u1 + tight && c.y() >= v0 - tight &&
             c.y() <= v1 + tight && c.z() >= c0 - tight && c.z() <= c1 + tight;
    };
    for (std::uint32_t i = 0; i < points_.size(); ++i) {
      if (!used_[i] && points_[i].allFinite() && inside_box(local(points_[i]))) {
        members.push_back(i);
      }
    }
    seed.used = true;
    if (round_section(members, seed, {v0, v1, c0, c1})) {
      out_.rejected.push_back({"box from plane " + std::to_string(seed.shape),
                               "a cylinder along its length fits its points better",
                               static_cast<long long>(members.size())});
      continue;
    }
    for (auto& other : patches_) {
      if (other.used) continue;
      std::size_t in = 0;
      for (auto i : other.members) in += inside_box(local(points_[i])) ? 1 : 0;
      if (in * 10 >= other.members.size() * 8) other.used = true;
    }
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
                             : patch.sagitta > 0.5 * ransac_.epsilon
                                 ? "no box: its points bow across it (a strip of a curved surface)"
                                 : "no box: no face of a box behind or before it is seen",
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
  if (spec.type == PrimitiveType::Cylinder || spec.type == PrimitiveType::Cone) {
    // One piece per axis: a round tower split by the RANSAC into cones (one inverted) keeps
    // the earlier, larger one.
    const std::string other = coaxial_overlap(spec);
    if (!other.empty()) {
      out_.rejected.push_back(
          {what, "overlaps the coaxial " + other, static_cast<long long>(members.size())});
      return;
    }
  }
  emit(std::move(spec), members, area, what);
}

// The id of a kept cylinder or cone on the same axis as `spec` (directions within the angle
// tolerance, axes within half the larger radius, or 2 ε, of each other) whose extent along
// the axis overlaps it; empty when none.
std::string Builder::coaxial_overlap(const PrimitiveSpec& spec) const {
  const Vec3 b = spec.placement.rotation().col(2).normalized();
  const Vec3 pb = spec.placement.translation();
  const double rb = std::max(spec.radius, spec.type == PrimitiveType::Cone ? spec.radius2 : 0.0);
  for (const auto& p : out_.primitives) {
    const PrimitiveSpec& q = p.spec;
    if (q.type != PrimitiveType::Cylinder && q.type != PrimitiveType::Cone) continue;
    const Vec3 a = q.placement.rotation().col(2).normalized();
    if (std::abs(a.dot(b)) < cos_tol_) continue;
    const Vec3 pa = q.placement.translation();
    const double ra = std::max(q.radius, q.type == PrimitiveType::Cone ? q.radius2 : 0.0);
    const double reach = std::max(0.5 * std::max(ra, rb), 2.0 * ransac_.epsilon);
    const Vec3 qb = pb + spec.height * b;
    auto off_axis = [&](const Vec3& x) {
      const Vec3 d = x - pa;
      return (d - d.dot(a) * a).norm();
    };
    if (off_axis(pb) > reach || off_axis(qb) > reach) continue;
    const double t0 = (pb - pa).dot(a), t1 = (qb - pa).dot(a);
    if (std::min(std::max(t0, t1), q.height) > std::max(std::min(t0, t1), 0.0)) return p.id;
  }
  return {};
}

// A proposal of several shapes (extrusion, revolution) kept when its solid is valid; its
// shapes then make nothing of their own. True when kept.
bool Builder::take(const detail::Proposal& proposal) {
  const std::size_t before = out_.primitives.size();
  emit(proposal.spec, proposal.members, proposal.area, proposal.what);
  if (out_.primitives.size() == before) return false;
  for (int s : proposal.shapes) absorbed_[static_cast<std::size_t>(s)] = 1;
  return true;
}

FittedPrimitives Builder::run() {
  absorbed_.assign(shapes_.shapes.size(), 0);
  const detail::ProposalInput in = proposal_input();
  if (o_.footprint != nullptr && !o_.footprint->empty()) {
    // A building in its footprint: its roof partition, else the footprint's block; nothing
    // else (one building per footprint, standing exactly on it).
    bool any = false;
    for (const auto& p : detail::propose_roof_partition(in, out_.rejected)) any = take(p) || any;
    if (!any) {
      for (const auto& p : detail::propose_footprint_block(in, out_.rejected)) take(p);
    }
    return std::move(out_);
  }
  if (o_.revolutions) {
    for (const auto& p : detail::propose_revolutions(in, out_.rejected)) take(p);
  }
  if (o_.extrusions && o_.roof_partition) {
    const auto parts = detail::propose_roof_partition(in, out_.rejected);
    for (const auto& p : parts) take(p);
    if (!parts.empty()) {
      // Shapes most of whose points the parts took make nothing of their own.
      for (std::size_t s = 0; s < shapes_.shapes.size(); ++s) {
        const auto& inl = shapes_.shapes[s].inliers;
        std::size_t taken = 0;
        for (auto i : inl) taken += used_[i] ? 1 : 0;
        if (2 * taken >= inl.size()) absorbed_[s] = 1;
      }
    }
  }
  if (o_.extrusions) {
    // One at a time: each kept extrusion takes its walls, the next is sought among the rest.
    for (int k = 0; k < 8; ++k) {
      const auto p = detail::propose_extrusion(in, out_.rejected);
      if (!p || !take(*p)) break;
    }
    for (int k = 0; k < 8; ++k) {
      const auto p = detail::propose_roof_extrusion(in, out_.rejected);
      if (!p || !take(*p)) break;
    }
    for (const auto& p : detail::propose_pitched_roofs(in, out_.rejected)) take(p);
    for (const auto& p : detail::propose_roof_parts(in, out_.rejected)) take(p);
  }
  if (o_.boxes) boxes();
  for (std::size_t s = 0; s < shapes_.shapes.size(); ++s) {
    const ShapeType type = shapes_.shapes[s].surface.type;
    if (absorbed_[s]) continue;
    if (type == ShapeType::Plane) {
      if (!o_.boxes) {
        out_.rejected.push_back({"plane " + std::to_string(s), "planes alone are not primitives",
                                 static_cast<long long>(shapes_.shapes[s].inliers.size())});
      }
      continue;
    }
    curved(static_cast<int>(s));
  }
  if (o_.extrusions) blocks();
  return std::move(out_);
}

// The region's points no kept primitive explains (inside one, or up to half a metre above
// it) become LoD1.2 blocks (blocks.cpp).
void Builder::blocks() {
  std::vector<geo::detail::PreparedPrimitive> kept;
  for (const auto& p : out_.primitives) kept.push_back(geo::detail::prepare_primitive(p.spec));
  const double above = std::max(0.5, 3.0 * ransac_.epsilon);
  auto explained = [&](const Vec3& q) {
    for (const auto& p : kept) {
      const kernel::BoundingBox& b = p.world_bounds;
      if (q.x() < b.min.x() || q.x() > b.max.x() || q.y() < b.min.y() || q.y() > b.max.y() ||
          q.z() < b.min.z() || q.z() > b.max.z() + above) {
        continue;
      }
      if (geo::detail::primitive_contains(p, q) ||
          geo::detail::primitive_contains(p, q - Vec3(0.0, 0.0, above))) {
        return true;
      }
    }
    return false;
  };
  for (const auto& p : detail::propose_blocks(proposal_input(), explained, out_.rejected)) {
    take(p);
  }
}

}  // namespace

FittedPrimitives primitives_from_shapes(std::span<const Vec3> points, std::span<const Vec3> normals,
                                        const RansacResult& shapes, const PrimitiveOptions& options,
                                        const RansacOptions& ransac, int region) {
  if (shapes.assignment.size() != points.size() ||
      (!normals.empty() && normals.size() != points.size())) {
    FittedPrimitives none;
    none.rejected.push_back({"region " + std::to_string(region),
                             "shapes or normals do not match the points (" +
                                 std::to_string(shapes.assignment.size()) + " assignments, " +
                                 std::to_string(normals.size()) + " normals, " +
                                 std::to_string(points.size()) + " points)",
                             static_cast<long long>(points.size())});
    return none;
  }
  Builder builder(points, normals, shapes, options, ransac, region);
  return builder.run();
}

}  // namespace csgtile::fit
