// Boxes from planes: a seed plane whose points fill their bounding rectangle, the nearest
// parallel plane facing it across the box (or, when none is seen, the points of orthogonal
// planes along its rectangle), so that a beam scanned on two or three sides is one box.

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <numbers>
#include <optional>
#include <set>
#include <tuple>

#include "csgtile/kernel/check.h"
#include "csgtile/kernel/mass_properties.h"
#include "fit_internal.h"
#include "plane2d.h"
#include "primitive_builder.h"

namespace csgtile::fit::detail {

namespace {

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

}  // namespace

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

std::vector<std::uint32_t> Builder::unused_in(const PlanePatch& seed, const SeedBox& box,
                                              double grow) const {
  std::vector<std::uint32_t> inside;
  for (std::uint32_t i = 0; i < points_.size(); ++i) {
    if (used_[i] || !points_[i].allFinite()) continue;
    const Vec3 d = points_[i] - seed.origin;
    const double a = d.dot(seed.u), b = d.dot(seed.v), c = d.dot(seed.n);
    if (a >= box.u0 - grow && a <= box.u1 + grow && b >= box.v0 - grow && b <= box.v1 + grow &&
        c >= box.c0 - grow && c <= box.c1 + grow) {
      inside.push_back(i);
    }
  }
  return inside;
}

std::optional<PrimitiveSpec> seed_box_spec(const PlanePatch& seed, const SeedBox& box) {
  const Eigen::Matrix3d rot = frame(seed.u, seed.v);
  const Vec3 corner = seed.origin + box.u0 * rot.col(0) + box.v0 * rot.col(1) + box.c0 * rot.col(2);
  return box_spec(rot, corner, Vec3(box.u1 - box.u0, box.v1 - box.v0, box.c1 - box.c0));
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
    // against the plane's noise (robust σ of the points over it, a pass over the region,
    // measured once and only when needed) and epsilon, not only the thinnest box.
    std::optional<double> noise;
    const auto no_own_depth = [&] {
      const double least = std::max(o_.min_box_thickness, 3.0 * ransac_.epsilon);
      if (c1 - c0 < least) return true;
      if (!noise) noise = robust_noise(points_, seed);
      return c1 - c0 < 4.0 * *noise;
    };
    const bool roof_wide =
        std::min(seed.umax - seed.umin, seed.vmax - seed.vmin) >= o_.min_building_width;
    // The seed's rectangle: its corners, its centre, and how far around it the terrain is
    // looked for (half its diagonal and two terrain cells).
    std::array<Vec3, 4> seed_corners;
    for (int k = 0; k < 4; ++k) {
      seed_corners[static_cast<std::size_t>(k)] = seed.origin +
                                                  (k < 2 ? seed.umin : seed.umax) * seed.u +
                                                  (k % 2 == 0 ? seed.vmin : seed.vmax) * seed.v;
    }
    const Vec3 centre = seed.origin + 0.5 * (seed.umin + seed.umax) * seed.u +
                        0.5 * (seed.vmin + seed.vmax) * seed.v;
    const auto terrain_reach = [&] {
      return 0.5 * std::hypot(seed.umax - seed.umin, seed.vmax - seed.vmin) + 2.0 * o_.ground->cell;
    };
    if (o_.ground != nullptr && std::abs(seed.n.z()) >= cos_tol_ && roof_wide && no_own_depth()) {
      // A roof seen from above: down to the terrain under it. Only for roofs wide enough to
      // be a building: a beam's underside seen from below has no depth of its own either.
      // The lowest terrain around the roof's footprint (not farther off), else near it.
      std::vector<Vec2> footprint;
      for (const Vec3& w : seed_corners) footprint.emplace_back(w.x(), w.y());
      double g = detail::lowest_ground_under(*o_.ground, detail::convex_hull(footprint));
      if (!std::isfinite(g)) g = o_.ground->lowest_near(centre.x(), centre.y(), terrain_reach());
      if (std::isfinite(g) && centre.z() - g >= o_.min_building_height) {
        const double c = (g - seed.origin.z()) * seed.n.z();
        c0 = std::min(0.0, c);
        c1 = std::max(0.0, c);
      }
    }
    if (c1 - c0 < o_.min_box_thickness) continue;
    // Over a terrain (an airborne scan), a plane as wide as a building whose only depth is its
    // own noise, and that did not reach down to the terrain above, is a surface seen from one
    // side — a pitched roof whose building no other step made, or raised ground — not a box a
    // few centimetres thick floating over the terrain. Named by its height over the terrain.
    if (o_.ground != nullptr && roof_wide && no_own_depth()) {
      double top = -INFINITY;
      for (const Vec3& w : seed_corners) top = std::max(top, w.z());
      const double terrain = o_.ground->lowest_near(centre.x(), centre.y(), terrain_reach());
      const bool low = std::isfinite(terrain) && top - terrain < o_.min_building_height;
      out_.rejected.push_back(
          {"box from plane " + std::to_string(seed.shape),
           low ? "no box: a surface with no depth of its own just over the terrain: raised "
                 "ground, no building"
               : "no box: a surface with no depth of its own over the terrain: a roof seen "
                 "from one side, its building not made",
           static_cast<long long>(seed.members.size())});
      seed.used = true;
      continue;
    }
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
    const SeedBox extent{u0, u1, v0, v1, c0, c1};
    std::vector<std::uint32_t> members = unused_in(seed, extent, tight);
    auto inside_box = [&](const Vec3& c) {
      return c.x() >= u0 - tight && c.x() <= u1 + tight && c.y() >= v0 - tight &&
             c.y() <= v1 + tight && c.z() >= c0 - tight && c.z() <= c1 + tight;
    };
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
    auto spec = seed_box_spec(seed, extent);
    if (!spec) continue;
    const double area = box_area(spec->size);
    emit(std::move(*spec), members, area, "box from plane " + std::to_string(seed.shape));
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

}  // namespace csgtile::fit::detail
