// Members of a frame, joined after the boxes and cylinders are built: a beam whose face the
// scan saw in pieces (a shadow across it) is one box, and a beam's end reaches the axis of
// the column or the middle of the member it runs into, as a frame's members meet, instead of
// stopping at the surface where its points stop.

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <numbers>
#include <optional>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include "column_ends.h"
#include "primitive_builder.h"
#include "synth/ray_internal.h"

namespace csgtile::fit::detail {

namespace {

// An elongated box in its own terms: its centre line from `start` along `u` over [0, length],
// its section's axes `a`, `b` and half-sizes.
struct Member {
  Vec3 start, u, a, b;
  double length = 0.0, half_a = 0.0, half_b = 0.0;
};

// The box as a member, when its longest side is at least twice its others.
std::optional<Member> as_member(const PrimitiveSpec& spec) {
  if (spec.type != PrimitiveType::Box || !spec.clips.empty()) return std::nullopt;
  const Eigen::Matrix3d& r = spec.placement.rotation();
  const double scale = spec.placement.scale();
  int k = 0;
  for (int i = 1; i < 3; ++i) {
    if (spec.size[i] > spec.size[k]) k = i;
  }
  const int i = (k + 1) % 3, j = (k + 2) % 3;
  if (spec.size[k] < 2.0 * std::max(spec.size[i], spec.size[j])) return std::nullopt;
  Member m;
  m.u = r.col(k);
  m.a = r.col(i);
  m.b = r.col(j);
  m.length = scale * spec.size[k];
  m.half_a = 0.5 * scale * spec.size[i];
  m.half_b = 0.5 * scale * spec.size[j];
  m.start = spec.placement.translation() + m.half_a * m.a + m.half_b * m.b;
  return m;
}

// The box spec of a member.
std::optional<PrimitiveSpec> member_spec(const Member& m) {
  return box_spec(frame(m.u, m.a), m.start - m.half_a * m.a - m.half_b * m.b,
                  Vec3(m.length, 2.0 * m.half_a, 2.0 * m.half_b));
}

// Where two lines p + s·u and q + t·w (unit directions) pass closest: s, t and the distance
// between the two points; nullopt when they are parallel.
struct Closest {
  double s = 0.0, t = 0.0, distance = 0.0;
};
std::optional<Closest> closest_approach(const Vec3& p, const Vec3& u, const Vec3& q,
                                        const Vec3& w) {
  const Vec3 d = p - q;
  const double b = w.dot(u), dd = u.dot(d), e = w.dot(d);
  const double denom = 1.0 - b * b;
  if (denom <= 1e-12) return std::nullopt;
  Closest c;
  c.s = (b * e - dd) / denom;
  c.t = (e - b * dd) / denom;
  c.distance = ((p + c.s * u) - (q + c.t * w)).norm();
  return c;
}

// What an end along `out` runs into: the target's axis line from `origin` over [0, extent],
// its half-size along `out` and beside the end's line.
struct Target {
  Vec3 axis, origin;
  double extent = 0.0, half = 0.0, across = 0.0;
};

// A cylinder as a target, in world terms (its radius both ways).
Target cylinder_target(const PrimitiveSpec& spec) {
  Target t;
  t.axis = spec.placement.rotation().col(2);
  t.origin = spec.placement.translation();
  t.half = t.across = spec.placement.scale() * spec.radius;
  t.extent = spec.placement.scale() * spec.height;
  return t;
}

// A member as a target for an end along `out`: the side of its section facing the end is
// `half`, the other `across`.
Target member_target(const Member& m, const Vec3& out) {
  Target t;
  t.axis = m.u;
  t.origin = m.start;
  t.extent = m.length;
  const bool a_along = std::abs(m.a.dot(out)) >= std::abs(m.b.dot(out));
  t.half = a_along ? m.half_a : m.half_b;
  t.across = a_along ? m.half_b : m.half_a;
  return t;
}

// The margins of a frame's members: `tight` the noise margin of a face, `reach` how far short
// of another member an end may stop and still meet it, `sin_tol` the sine of the fit's angle
// tolerance (how far from across a crossing axis may turn).
struct Margins {
  double tight = 0.0, reach = 0.0, sin_tol = 0.0;
};
Margins margins(double epsilon, double cell, double cos_tol) {
  Margins m;
  m.tight = std::max(2.0 * epsilon, 0.5 * cell);
  m.reach = std::max(m.tight, cell);
  m.sin_tol = std::sqrt(std::max(0.0, 1.0 - cos_tol * cos_tol));
  return m;
}

// Members of a frame repeat: their axes are parallel (GlobFit's first relation). A member
// fitted from a piece of one face takes that piece's direction, degrees off its siblings'
// (a 4 degree tilt lifts the far end of a 3 m beam by 0.2 m, and its end then misses the
// column it runs into). Directions within the angle tolerance of each other form a group,
// heaviest member first (weight: length); a group of two or more has one direction, the
// principal axis of its members' directions weighted by their lengths, and each member turns
// onto it about its own centre (its section turned with it). Returns which members turned.
std::vector<char> parallel_members(std::vector<std::optional<Member>>& members, double cos_tol) {
  std::vector<std::size_t> order;
  for (std::size_t k = 0; k < members.size(); ++k) {
    if (members[k]) order.push_back(k);
  }
  std::stable_sort(order.begin(), order.end(), [&](std::size_t x, std::size_t y) {
    return members[x]->length > members[y]->length;
  });
  std::vector<char> grouped(members.size(), 0), turned(members.size(), 0);
  for (const std::size_t lead : order) {
    if (grouped[lead]) continue;
    const Vec3 d0 = members[lead]->u;
    std::vector<std::size_t> group;
    for (const std::size_t k : order) {
      if (!grouped[k] && std::abs(members[k]->u.dot(d0)) >= cos_tol) {
        grouped[k] = 1;
        group.push_back(k);
      }
    }
    if (group.size() < 2) continue;
    Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
    for (const std::size_t k : group)
      scatter += members[k]->length * members[k]->u * members[k]->u.transpose();
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(scatter);
    Vec3 d = eigen.eigenvectors().col(2).normalized();
    if (d.dot(d0) < 0.0) d = -d;
    for (const std::size_t k : group) {
      Member& m = *members[k];
      const Vec3 target = m.u.dot(d) < 0.0 ? Vec3(-d) : d;
      if (target == m.u) continue;
      const Eigen::Matrix3d turn =
          Eigen::Quaterniond::FromTwoVectors(m.u, target).toRotationMatrix();
      const Vec3 centre = m.start + 0.5 * m.length * m.u;
      const Vec3 a = turn * m.a;
      m.u = target;
      m.a = (a - a.dot(target) * target).normalized();
      m.b = target.cross(m.a);  // as as_member's frame: u, a, b right-handed
      m.start = centre - 0.5 * m.length * m.u;
      turned[k] = 1;
    }
  }
  return turned;
}

}  // namespace

// A beam seen on one face only (its other faces hidden or too sparse for a depth) takes the
// section its siblings show: among the boxes parallel to it, those with a side as wide as the
// face give the depth across it (their median). Which side of the face the box lies on is
// told by the columns: a frame's members run through their axes, so the side whose centre
// line passes through the axis of a column (within twice epsilon or a quarter of the depth)
// no farther beyond one of its ends than its own length is taken; when neither or both do, no
// box is made. A column's top may end below the members it carries (hidden among them): its
// axis counts up to a member's depth above its fitted top. The face may be seen in pieces of
// one plane (joined first) and its plane may hold strips of the columns it passes (trimmed to
// the face's band); a face twice as long as it is wide is enough, the siblings confirming what
// it is. join_members then takes its ends to the columns.
void Builder::one_face_members() {
  // Plain variables, not a structured binding: the lambdas below capture them.
  const Margins margin = margins(ransac_.epsilon, cell_, cos_tol_);
  const double tight = margin.tight, reach = margin.reach, sin_tol = margin.sin_tol;
  std::vector<Member> siblings;
  for (const auto& p : out_.primitives) {
    if (auto m = as_member(p.spec)) siblings.push_back(*m);
  }
  // A face whose plane also took strips of the columns it passes (a column's surface crosses
  // the plane of a beam's face along a vertical line, its points within epsilon there) covers
  // too little of the rectangle around it: its band along one side of the patch where most
  // of its points lie (bins of a cell holding at least half the fullest one's, around it),
  // along the side whose band covers its rectangle better, is the face.
  auto dominant_band = [&](const PlanePatch& patch) -> std::optional<PlanePatch> {
    std::optional<PlanePatch> best;
    for (const Vec3& axis : {patch.u, patch.v}) {
      std::vector<long long> bin_of;  // per member
      std::map<long long, int> bins;
      bin_of.reserve(patch.members.size());
      for (auto i : patch.members) {
        bin_of.push_back(
            static_cast<long long>(std::floor((points_[i] - patch.origin).dot(axis) / cell_)));
        ++bins[bin_of.back()];
      }
      auto top = bins.begin();
      for (auto it = bins.begin(); it != bins.end(); ++it) {
        if (it->second > top->second) top = it;
      }
      long long lo = top->first, hi = top->first;
      const auto full = [&](long long b) {
        const auto it = bins.find(b);
        return it != bins.end() && 2 * it->second >= top->second;
      };
      while (full(lo - 1)) --lo;
      while (full(hi + 1)) ++hi;
      std::vector<std::uint32_t> kept;
      for (std::size_t k = 0; k < patch.members.size(); ++k) {
        if (bin_of[k] >= lo && bin_of[k] <= hi) kept.push_back(patch.members[k]);
      }
      if (kept.size() == patch.members.size() ||
          static_cast<long long>(kept.size()) < std::max<long long>(3, ransac_.min_points / 4)) {
        continue;
      }
      PlanePatch p = make_patch(points_, shapes_.shapes[static_cast<std::size_t>(patch.shape)],
                                patch.shape, std::move(kept), cell_);
      if (!best || p.coverage > best->coverage) best = std::move(p);
    }
    return best;
  };
  // Pieces of one plane (one RANSAC plane, or planes within the noise margin of each other) in
  // one band across it, with nothing standing between them along it, are one face the scan
  // saw in pieces (sparse rows, shadows): one patch. A column between
  // two pieces (its axis across their line, within its radius and the band's width of the
  // plane) keeps them apart: two members meeting there.
  struct Work {
    std::vector<std::size_t> parts;  // indices in patches_
    PlanePatch patch;
  };
  std::vector<Work> work;
  {
    std::vector<char> grouped(patches_.size(), 0);
    auto extent_in = [&](const PlanePatch& frame, const PlanePatch& p) {
      std::array<double, 4> e{INFINITY, -INFINITY, INFINITY, -INFINITY};
      for (auto i : p.members) {
        const Vec3 d = points_[i] - frame.origin;
        e[0] = std::min(e[0], d.dot(frame.u)), e[1] = std::max(e[1], d.dot(frame.u));
        e[2] = std::min(e[2], d.dot(frame.v)), e[3] = std::max(e[3], d.dot(frame.v));
      }
      return e;
    };
    auto column_between = [&](const PlanePatch& frame, double u0, double u1) {
      for (const auto& p : out_.primitives) {
        if (p.spec.type != PrimitiveType::Cylinder) continue;
        const Vec3 axis = p.spec.placement.rotation().col(2);
        if (std::abs(axis.dot(frame.u)) > sin_tol) continue;
        const double r = p.spec.placement.scale() * p.spec.radius;
        const Vec3 d = p.spec.placement.translation() - frame.origin;
        const double width = frame.vmax - frame.vmin;
        if (std::abs(d.dot(frame.n)) > r + width) continue;
        const double at = d.dot(frame.u);
        if (at > u0 - r && at < u1 + r) return true;
      }
      return false;
    };
    // The longest member parallel to a patch (members of a frame repeat): a join longer than
    // it would reach across a column the fit did not make, which nothing else tells.
    auto longest_parallel = [&](const PlanePatch& patch) {
      double longest = 0.0;
      for (const Member& m : siblings) {
        if (std::abs(m.u.dot(patch.u)) >= cos_tol_) longest = std::max(longest, m.length);
      }
      return longest;
    };
    for (std::size_t i = 0; i < patches_.size(); ++i) {
      if (patches_[i].used || grouped[i]) continue;
      grouped[i] = 1;
      Work w{{i}, patches_[i]};
      double longest = longest_parallel(w.patch);
      for (bool grew = true; grew;) {
        grew = false;
        for (std::size_t j = 0; j < patches_.size(); ++j) {
          if (grouped[j] || patches_[j].used) continue;
          // Of one plane: the same RANSAC plane, or another one on it (its connectivity split).
          const PlanePatch& o = patches_[j];
          if (o.shape != w.patch.shape &&
              (std::abs(o.n.dot(w.patch.n)) < cos_tol_ ||
               std::abs((o.origin - w.patch.origin).dot(w.patch.n)) > tight)) {
            continue;
          }
          const auto e = extent_in(w.patch, patches_[j]);
          const double overlap = std::min(e[3], w.patch.vmax) - std::max(e[2], w.patch.vmin);
          if (overlap < 0.5 * std::min(e[3] - e[2], w.patch.vmax - w.patch.vmin)) continue;
          const double g0 = e[0] > w.patch.umax ? w.patch.umax : e[1];
          const double g1 = e[0] > w.patch.umax ? e[0] : w.patch.umin;
          if (g1 > g0 && column_between(w.patch, g0, g1)) continue;
          const double joined = std::max(e[1], w.patch.umax) - std::min(e[0], w.patch.umin);
          if (joined > 1.1 * longest) continue;
          std::vector<std::uint32_t> both = w.patch.members;
          both.insert(both.end(), patches_[j].members.begin(), patches_[j].members.end());
          std::sort(both.begin(), both.end());
          w.patch = make_patch(points_, shapes_.shapes[static_cast<std::size_t>(w.patch.shape)],
                               w.patch.shape, std::move(both), cell_);
          w.parts.push_back(j);
          grouped[j] = 1;
          grew = true;
          longest = longest_parallel(w.patch);
        }
      }
      work.push_back(std::move(w));
    }
  }
  for (Work& item : work) {
    PlanePatch& patch = item.patch;
    std::optional<PlanePatch> band;
    if (patch.coverage < o_.min_seed_coverage) {
      band = dominant_band(patch);
      if (!band || band->coverage < o_.min_seed_coverage) continue;
    }
    PlanePatch& seed = band ? *band : patch;
    const double length = seed.umax - seed.umin, width = seed.vmax - seed.vmin;
    if (seed.sagitta > 0.5 * ransac_.epsilon) continue;
    if (length < 2.0 * width || width < o_.min_box_thickness) continue;
    std::vector<double> depths;
    for (const Member& m : siblings) {
      if (std::abs(m.u.dot(seed.u)) < cos_tol_) continue;
      const double size_tol = std::max(2.0 * ransac_.epsilon, 0.1 * width);
      if (std::abs(2.0 * m.half_a - width) <= size_tol) depths.push_back(2.0 * m.half_b);
      if (std::abs(2.0 * m.half_b - width) <= size_tol) depths.push_back(2.0 * m.half_a);
    }
    if (depths.empty()) continue;
    std::nth_element(depths.begin(),
                     depths.begin() + static_cast<std::ptrdiff_t>(depths.size() / 2), depths.end());
    const double depth = depths[depths.size() / 2];
    if (depth < o_.min_box_thickness) continue;
    const Vec3 mid = seed.origin + 0.5 * (seed.vmin + seed.vmax) * seed.v;
    int chosen = 0;
    for (const double side : {-1.0, 1.0}) {
      const Vec3 line = mid + 0.5 * depth * side * seed.n;  // centre line through origin + a·u
      bool through = false;
      for (const auto& p : out_.primitives) {
        if (p.spec.type != PrimitiveType::Cylinder) continue;
        const Vec3 axis = p.spec.placement.rotation().col(2);
        if (std::abs(axis.dot(seed.u)) > sin_tol) continue;
        const double r = p.spec.placement.scale() * p.spec.radius;
        const auto pass = closest_approach(line, seed.u, p.spec.placement.translation(), axis);
        if (!pass) continue;
        const double at_end =
            std::min(std::abs(pass->s - seed.umin), std::abs(pass->s - seed.umax));
        if (pass->distance <= std::max(2.0 * ransac_.epsilon, 0.25 * depth) &&
            at_end <= r + reach + length && pass->t >= -tight &&
            pass->t <= p.spec.placement.scale() * p.spec.height + tight + depth) {
          through = true;
          break;
        }
      }
      if (through) chosen = chosen == 0 ? static_cast<int>(side) : 2;
    }
    if (chosen != -1 && chosen != 1) continue;
    const double c0 = chosen < 0 ? -depth : 0.0, c1 = chosen < 0 ? 0.0 : depth;
    const SeedBox extent{seed.umin, seed.umax, seed.vmin, seed.vmax, c0, c1};
    const std::vector<std::uint32_t> members = unused_in(seed, extent, tight);
    for (std::size_t k : item.parts) patches_[k].used = true;
    auto spec = seed_box_spec(seed, extent);
    if (!spec) continue;
    const double area = box_area(spec->size);
    emit(std::move(*spec), members, area,
         "box from plane " + std::to_string(seed.shape) + " seen on one face");
  }
}

// Two boxes are one member seen in pieces when their axes are parallel (within the angle
// tolerance), their sections equal and on one line (within the fit's noise margin), and
// nothing lies between them along that line: no other primitive, and no points facing along
// it within the section (an end face, a column the scan saw but the fit did not make). The
// gap they leave is at most the shorter piece (a shadow is no longer than what is seen on
// both sides of it). Then each member's ends reach into what they run into: when the centre
// line, continued past an end by at most the noise margin, enters a column (a cylinder whose
// axis is across it) or a member crossing it, the end moves to that column's axis or that
// member's middle. Changed boxes are built again (emit) with their points; one refused keeps
// the boxes it came from.
void Builder::join_members() {
  // Plain variables, not a structured binding: the lambdas below capture them.
  const Margins margin = margins(ransac_.epsilon, cell_, cos_tol_);
  const double tight = margin.tight, reach = margin.reach, sin_tol = margin.sin_tol;
  std::vector<geo::detail::PreparedPrimitive> prepared;
  prepared.reserve(out_.primitives.size());
  for (const auto& p : out_.primitives) prepared.push_back(geo::detail::prepare_primitive(p.spec));
  std::vector<std::optional<Member>> members(out_.primitives.size());
  for (std::size_t k = 0; k < members.size(); ++k) members[k] = as_member(out_.primitives[k].spec);
  const std::vector<char> turned = parallel_members(members, cos_tol_);
  std::vector<std::vector<std::size_t>> joined;  // groups of primitive indices, one member each
  std::vector<int> group_of(members.size(), -1);
  std::vector<Member> merged;
  // Whether anything stands on the centre line of `m` over (t0, t1).
  auto blocked = [&](const Member& m, double t0, double t1, const std::vector<std::size_t>& skip,
                     bool to_target) {
    const double step = std::max(0.25 * cell_, 1e-3);
    for (double t = t0; t <= t1; t += step) {
      const Vec3 q = m.start + t * m.u;
      for (std::size_t k = 0; k < prepared.size(); ++k) {
        if (std::find(skip.begin(), skip.end(), k) != skip.end()) continue;
        const auto& box = prepared[k].world_bounds;
        if (q.x() < box.min.x() || q.x() > box.max.x() || q.y() < box.min.y() ||
            q.y() > box.max.y() || q.z() < box.min.z() || q.z() > box.max.z()) {
          continue;
        }
        if (geo::detail::primitive_contains(prepared[k], q)) return true;
      }
    }
    // Points facing along the line within the section: three of them stop a join of two
    // pieces (a node between them whose members the fit did not make). An end going on to the
    // member it runs into stops only at a surface across the line: three facing points in one
    // cell's length along it. Facing normals scattered along the way are the noise of the
    // member's own edges (normals of a few neighbours across a corner), not a surface.
    int facing = 0;
    std::map<long long, int> slabs;  // cell along the line: facing points
    for (std::size_t i = 0; i < points_.size(); ++i) {
      if (normals_.empty() || !points_[i].allFinite()) continue;
      const Vec3 d = points_[i] - m.start;
      const double t = d.dot(m.u);
      if (t <= t0 || t >= t1) continue;
      if (std::abs(d.dot(m.a)) > m.half_a + tight || std::abs(d.dot(m.b)) > m.half_b + tight) {
        continue;
      }
      if (std::abs(normals_[i].dot(m.u)) < 0.5) continue;
      if (!to_target) {
        if (++facing >= 3) return true;
      } else if (++slabs[static_cast<long long>(std::floor(t / cell_))] >= 3) {
        return true;
      }
    }
    return false;
  };
  // Whether the scan saw the member's faces over (t0, t1): points within its section (grown by
  // the noise margin) near one of its faces, their normals across its line, in at least two
  // cells along it. Behind a shadow, the member shows itself again before what it runs into.
  auto seen_over = [&](const Member& m, double t0, double t1) {
    std::vector<long long> cells;
    for (std::size_t i = 0; i < points_.size(); ++i) {
      if (normals_.empty() || !points_[i].allFinite() || !normals_[i].allFinite()) continue;
      const Vec3 d = points_[i] - m.start;
      const double t = d.dot(m.u);
      if (t <= t0 || t >= t1) continue;
      const double a = std::abs(d.dot(m.a)), b = std::abs(d.dot(m.b));
      if (a > m.half_a + tight || b > m.half_b + tight) continue;
      if (a < m.half_a - tight && b < m.half_b - tight) continue;  // inside, on no face
      if (std::abs(normals_[i].dot(m.u)) >= 0.5) continue;
      cells.push_back(static_cast<long long>(std::floor(t / cell_)));
    }
    std::sort(cells.begin(), cells.end());
    return cells.size() >= 5 && std::unique(cells.begin(), cells.end()) - cells.begin() >= 2;
  };
  for (std::size_t x = 0; x < members.size(); ++x) {
    if (!members[x] || group_of[x] >= 0) continue;
    Member m = *members[x];
    std::vector<std::size_t> group{x};
    for (bool grew = true; grew;) {
      grew = false;
      for (std::size_t y = 0; y < members.size(); ++y) {
        if (y == x || !members[y] || group_of[y] >= 0 ||
            std::find(group.begin(), group.end(), y) != group.end()) {
          continue;
        }
        const Member& o = *members[y];
        if (std::abs(o.u.dot(m.u)) < cos_tol_) continue;
        // The other's section axes matched to ours, sizes and centre lines compared.
        const bool swapped = std::abs(o.a.dot(m.a)) < std::abs(o.b.dot(m.a));
        const double oa = swapped ? o.half_b : o.half_a, ob = swapped ? o.half_a : o.half_b;
        const double size_tol = std::max(tight, 0.1 * std::min(m.half_a, m.half_b));
        if (std::abs(oa - m.half_a) > size_tol || std::abs(ob - m.half_b) > size_tol) continue;
        const Vec3 d = o.start - m.start;
        if (std::abs(d.dot(m.a)) > size_tol || std::abs(d.dot(m.b)) > size_tol) continue;
        const double s0 = d.dot(m.u), s1 = s0 + o.length * o.u.dot(m.u);
        const double lo = std::min(s0, s1), hi = std::max(s0, s1);
        const double gap = lo > m.length ? lo - m.length : hi < 0.0 ? -hi : 0.0;
        if (gap > std::min(m.length, hi - lo)) continue;
        std::vector<std::size_t> skip = group;
        skip.push_back(y);
        if (gap > 0.0 && (lo > m.length ? blocked(m, m.length, lo, skip, false)
                                        : blocked(m, hi, 0.0, skip, false))) {
          continue;
        }
        // One member over both: the longer piece's frame, the union of the two extents.
        const double t0 = std::min(0.0, lo), t1 = std::max(m.length, hi);
        m.start += t0 * m.u;
        m.length = t1 - t0;
        group.push_back(y);
        grew = true;
      }
    }
    for (std::size_t k : group) group_of[k] = static_cast<int>(joined.size());
    joined.push_back(std::move(group));
    merged.push_back(m);
  }
  // Ends into what they run into.
  for (std::size_t g = 0; g < merged.size(); ++g) {
    Member& m = merged[g];
    const auto& group = joined[g];
    for (const double side : {-1.0, 1.0}) {
      const Vec3 end = m.start + (side > 0.0 ? m.length : 0.0) * m.u;
      const Vec3 out = side * m.u;
      double best = INFINITY;  // distance past the end to the target's axis or middle
      double far = INFINITY;   // the same for a target farther than the noise margin
      std::size_t far_target = 0;
      double far_half = 0.0;
      for (std::size_t k = 0; k < out_.primitives.size(); ++k) {
        if (std::find(group.begin(), group.end(), k) != group.end()) continue;
        const PrimitiveSpec& t = out_.primitives[k].spec;
        Target target;
        if (t.type == PrimitiveType::Cylinder) {
          target = cylinder_target(t);
        } else if (const auto& c = members[k]) {
          target = member_target(*c, out);
        } else {
          continue;
        }
        const double half = target.half, extent = target.extent;
        if (std::abs(target.axis.dot(out)) > sin_tol) continue;
        // The target's axis line and the member's centre line: where they pass closest.
        const auto pass = closest_approach(end, out, target.origin, target.axis);
        if (!pass || pass->distance > target.across) continue;
        // A column's top hidden among the members it carries (the scan sees no surface there)
        // ends its fit up to a member's section below them.
        const double hidden =
            t.type == PrimitiveType::Cylinder ? 2.0 * std::max(m.half_a, m.half_b) : 0.0;
        if (pass->t < -tight || pass->t > extent + tight + hidden) continue;
        const double s = pass->s;  // along `out` from the end
        // The end between the target's near surface (less the noise margin) and its axis.
        if (s < 0.0) continue;
        if (s <= half + reach) {
          best = std::min(best, s);
        } else if (s < far) {
          far = s;
          far_target = k;
          far_half = half;
        }
      }
      if (!std::isfinite(best) && std::isfinite(far)) {
        // A free end (a member meets another; it does not stop in the air) goes on to the
        // next member along its line, no farther than its own length, over a stretch where
        // nothing stands and no points face along it (a shadow, not an end).
        std::vector<std::size_t> skip = group;
        skip.push_back(far_target);
        // Up to the target's near side (its own surface faces along the line). Farther than
        // its own length only where its faces are seen again over the last third of the way.
        const double open = std::max(0.0, far - far_half - reach);
        const double t0 = side > 0.0 ? m.length : -open, t1 = side > 0.0 ? m.length + open : 0.0;
        const double last = open / 3.0;
        const bool evidence =
            far - far_half <= m.length ||
            (side > 0.0 ? seen_over(m, t1 - last, t1) : seen_over(m, t0, t0 + last));
        if (evidence && !blocked(m, t0, t1, skip, true)) best = far;
      }
      if (!std::isfinite(best)) continue;
      if (side > 0.0) {
        m.length += best;
      } else {
        m.start -= best * m.u;
        m.length += best;
      }
    }
  }
  // Rebuild what changed where the first of its pieces stood; a refused rebuild leaves its
  // pieces there as they were. Ids are numbered again by position.
  std::vector<geo::ScenePrimitive> originals = std::move(out_.primitives);
  std::vector<std::vector<std::uint32_t>> original_members = std::move(emitted_members_);
  out_.primitives.clear();
  emitted_members_.clear();
  bool renumber = false;
  for (std::size_t k = 0; k < originals.size(); ++k) {
    const int g = group_of[k];
    const bool changed =
        g >= 0 && (joined[static_cast<std::size_t>(g)].size() > 1 || turned[k] ||
                   merged[static_cast<std::size_t>(g)].length != members[k]->length);
    if (!changed) {
      out_.primitives.push_back(std::move(originals[k]));
      emitted_members_.push_back(std::move(original_members[k]));
      continue;
    }
    const auto& group = joined[static_cast<std::size_t>(g)];
    if (group.front() != k) continue;  // rebuilt with the first of its group
    renumber = true;
    std::vector<std::uint32_t> points;
    std::string what = "member of";
    for (std::size_t j : group) {
      points.insert(points.end(), original_members[j].begin(), original_members[j].end());
      what += " " + originals[j].id;
      --out_.per_type[static_cast<std::size_t>(originals[j].spec.type)];
      out_.assigned_points -= originals[j].quality ? originals[j].quality->inliers : 0;
    }
    std::sort(points.begin(), points.end());
    points.erase(std::unique(points.begin(), points.end()), points.end());
    const std::size_t before = out_.primitives.size();
    if (auto spec = member_spec(merged[static_cast<std::size_t>(g)])) {
      const double area = box_area(spec->size);
      emit(std::move(*spec), points, area, what);
    }
    if (out_.primitives.size() > before) continue;
    for (std::size_t j : group) {
      ++out_.per_type[static_cast<std::size_t>(originals[j].spec.type)];
      out_.assigned_points += originals[j].quality ? originals[j].quality->inliers : 0;
      out_.primitives.push_back(std::move(originals[j]));
      emitted_members_.push_back(std::move(original_members[j]));
    }
  }
  if (!renumber) return;
  for (std::size_t k = 0; k < out_.primitives.size(); ++k) {
    out_.primitives[k].id = "r" + std::to_string(region_) + "-" + std::to_string(k);
  }
}

}  // namespace csgtile::fit::detail

namespace csgtile::fit::detail {

double member_reach(double epsilon, double cluster_epsilon) {
  return margins(epsilon, connectivity_cell(cluster_epsilon, epsilon), 1.0).reach;
}

int columns_into_members(std::vector<geo::ScenePrimitive>& primitives,
                         std::span<const double> reach, double cos_tol) {
  const double sin_tol = std::sqrt(std::max(0.0, 1.0 - cos_tol * cos_tol));
  // A column: an elongated cylinder without clips, as a target (`half` its radius).
  auto as_column = [](const PrimitiveSpec& spec) -> std::optional<Target> {
    if (spec.type != PrimitiveType::Cylinder || !spec.clips.empty()) return std::nullopt;
    const Target c = cylinder_target(spec);
    if (!(c.half > 0.0) || c.extent < 4.0 * c.half) return std::nullopt;
    return c;
  };
  std::vector<std::optional<Member>> members(primitives.size());
  std::vector<std::optional<Target>> columns(primitives.size());
  for (std::size_t k = 0; k < primitives.size(); ++k) {
    members[k] = as_member(primitives[k].spec);
    columns[k] = as_column(primitives[k].spec);
  }
  int moved = 0;
  for (std::size_t c = 0; c < primitives.size(); ++c) {
    if (!columns[c]) continue;
    const Target& col = *columns[c];
    const double margin = c < reach.size() ? reach[c] : 0.0;
    double grow_low = 0.0, grow_high = 0.0;
    for (const double side : {-1.0, 1.0}) {
      const Vec3 end = col.origin + (side > 0.0 ? col.extent : 0.0) * col.axis;
      const Vec3 out = side * col.axis;
      double best = INFINITY;  // past the end to the member's middle
      for (std::size_t k = 0; k < primitives.size(); ++k) {
        if (k == c) continue;
        Target t;
        if (columns[k]) {
          t = *columns[k];
        } else if (members[k]) {
          t = member_target(*members[k], out);
        } else {
          continue;
        }
        if (std::abs(t.axis.dot(out)) > sin_tol) continue;
        const auto pass = closest_approach(end, out, t.origin, t.axis);
        if (!pass || pass->distance > t.across) continue;
        // A member that stops at the column's side (its end where its points stop) is still
        // the one it carries.
        const double beside = col.half + margin;
        if (pass->t < -beside || pass->t > t.extent + beside) continue;
        if (pass->s > 0.0 && pass->s <= t.half + margin) best = std::min(best, pass->s);
      }
      if (!std::isfinite(best)) continue;
      (side > 0.0 ? grow_high : grow_low) = best;
    }
    if (grow_low == 0.0 && grow_high == 0.0) continue;
    geo::ScenePrimitive& p = primitives[c];
    const double scale = p.spec.placement.scale();
    auto loc =
        Location::from_parts(p.spec.placement.rotation(), scale, col.origin - grow_low * col.axis);
    if (!loc.ok()) continue;
    moved += (grow_low > 0.0 ? 1 : 0) + (grow_high > 0.0 ? 1 : 0);
    const double length = col.extent + grow_low + grow_high;
    p.spec.placement = loc.value();
    p.spec.height = length / scale;
    // The points cover what they covered: the share of a longer side is smaller.
    if (p.quality) p.quality->coverage *= col.extent / length;
  }
  return moved;
}

}  // namespace csgtile::fit::detail
