// Higher-level primitives from several shapes: extrusions from planes parallel to one
// direction (walls and roof slopes around a section), revolutions from coaxial cylinders and
// cones with the planes ⟂ their axis. Both build a closed profile from the shapes' traces in
// the profile plane (chain_profile), and both are checked by the caller as kernel solids.
//
// Model selection (extrusions): a description length in points, L = points of the region
// left unexplained + λ · parameters, λ = ½·log2(points of the region); the extrusion (2 per
// profile vertex + h + 6 of placement) is kept only when its L is below that of the box
// around its profile (9 parameters), so a plain box stays a box and an L-shaped building is
// one extrusion rather than a box that misses its inner walls.

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

#include "fit_internal.h"
#include "plane2d.h"

namespace csgtile::fit::detail {

namespace {

using kernel::PrimitiveType;
using kernel::Vec2;

// Removes repeated vertices and vertices on the line of their neighbours.
std::vector<Vec2> clean_ring(std::vector<Vec2> ring, double tiny) {
  bool changed = true;
  while (changed && ring.size() >= 3) {
    changed = false;
    for (std::size_t i = 0; i < ring.size() && ring.size() >= 3; ++i) {
      const Vec2& p = ring[(i + ring.size() - 1) % ring.size()];
      const Vec2& q = ring[i];
      const Vec2& r = ring[(i + 1) % ring.size()];
      const double pq = (q - p).norm(), qr = (r - q).norm();
      const bool repeated = pq <= tiny;
      // Off the line p–r by less than `tiny`, and not a spike back along it.
      const bool straight = pq > tiny && qr > tiny && (r - p).norm() > tiny &&
                            std::abs(cross2(q - p, r - p)) / (r - p).norm() <= tiny &&
                            (q - p).dot(r - q) > 0.0;
      if (repeated || straight) {
        ring.erase(ring.begin() + static_cast<std::ptrdiff_t>(i));
        changed = true;
        break;
      }
    }
  }
  return ring;
}

// A prism: an outer ring, holes, and heights [0, h] along its direction.
struct Prism {
  std::vector<Vec2> outer;
  std::vector<std::vector<Vec2>> holes;
  double h = 0.0;
  // Distance from a point (x, y in the section, z along the direction) to its surface.
  double distance(const Vec2& q, double z) const {
    const double side = boundary_distance(q, outer, holes);
    const bool in = inside_polygon(q, outer, holes);
    const double dz = z < 0.0 ? -z : (z > h ? z - h : 0.0);
    if (dz == 0.0) return in ? std::min({side, z, h - z}) : side;
    return in ? dz : std::hypot(side, dz);
  }
};

// Splits the projections `s` (sorted with their indices) of a shape's inliers on its trace
// into runs without gaps wider than `gap`.
std::vector<std::pair<double, double>> runs(std::vector<double> s, double gap, std::size_t least) {
  std::sort(s.begin(), s.end());
  std::vector<std::pair<double, double>> out;
  std::size_t start = 0;
  for (std::size_t i = 1; i <= s.size(); ++i) {
    if (i == s.size() || s[i] - s[i - 1] > gap) {
      if (i - start >= least) out.emplace_back(s[start], s[i - 1]);
      start = i;
    }
  }
  return out;
}

double deg(double d) { return d * std::numbers::pi / 180.0; }

}  // namespace

std::vector<std::vector<Vec2>> chain_profile(const std::vector<ProfileSegment>& segments,
                                             double reach) {
  std::vector<std::size_t> order(segments.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](std::size_t x, std::size_t y) {
    return (segments[x].b - segments[x].a).norm() > (segments[y].b - segments[y].a).norm();
  });
  std::vector<char> done(segments.size(), 0);
  std::vector<std::vector<Vec2>> rings;
  const double sin_parallel = std::sin(deg(10.0));
  // Vertices joining the segment left at `p` (direction `dp`) to the one entered at `q`.
  auto join = [&](const Vec2& p, const Vec2& dp, const Vec2& q, const Vec2& dq,
                  std::vector<Vec2>& ring) {
    const double c = cross2(dp, dq);
    if (std::abs(c) > sin_parallel * dp.norm() * dq.norm()) {
      const double t = cross2(q - p, dq) / c;
      const Vec2 x = p + t * dp;
      const double lim = std::max(reach, 2.0 * (q - p).norm());
      if ((x - p).norm() <= lim && (x - q).norm() <= lim) {
        ring.push_back(x);
        return;
      }
    }
    ring.push_back(p);
    ring.push_back(q);
  };
  for (std::size_t first : order) {
    if (done[first]) continue;
    done[first] = 1;
    std::vector<Vec2> ring;
    const Vec2 start = segments[first].a;
    const Vec2 start_dir = segments[first].b - segments[first].a;
    Vec2 end = segments[first].b, dir = start_dir;
    std::size_t used = 1;
    for (;;) {
      double best = (end - start).norm();
      std::size_t next = segments.size();
      bool flip = false;
      for (std::size_t k : order) {
        if (done[k]) continue;
        const double da = (segments[k].a - end).norm(), db = (segments[k].b - end).norm();
        if (da < best) {
          best = da;
          next = k;
          flip = false;
        }
        if (db < best) {
          best = db;
          next = k;
          flip = true;
        }
      }
      if (next == segments.size()) {
        join(end, dir, start, start_dir, ring);
        break;
      }
      done[next] = 1;
      ++used;
      const Vec2 in = flip ? segments[next].b : segments[next].a;
      const Vec2 out = flip ? segments[next].a : segments[next].b;
      join(end, dir, in, out - in, ring);
      end = out;
      dir = out - in;
    }
    if (used < 2) continue;
    // Vertices are joins: the ring's start vertex is the last join, keep the order.
    double extent = 0.0;
    for (const auto& p : ring) extent = std::max(extent, p.norm());
    ring = clean_ring(std::move(ring), 1e-6 * std::max(1.0, extent));
    if (ring.size() < 3 || std::abs(ring_area(ring)) <= 1e-9 * std::max(1.0, extent * extent)) {
      continue;
    }
    rings.push_back(std::move(ring));
  }
  return rings;
}

std::vector<Proposal> propose_revolutions(const ProposalInput& in,
                                          std::vector<Rejection>& rejected) {
  std::vector<Proposal> out;
  const auto& shapes = in.shapes->shapes;
  const double tol = deg(in.options->angle_tolerance_deg);
  const double eps = in.ransac->epsilon;
  const double near_axis = std::max(4.0 * eps, in.cell);
  std::vector<int> curved;
  for (std::size_t s = 0; s < shapes.size(); ++s) {
    const auto t = shapes[s].surface.type;
    if ((*in.absorbed)[s]) continue;
    if ((t != ShapeType::Cylinder && t != ShapeType::Cone && t != ShapeType::Torus) ||
        static_cast<long long>(shapes[s].inliers.size()) < in.ransac->min_points) {
      continue;
    }
    // Strips of a surface (a few tens of degrees of a column) are no piece of a profile.
    const Surface& cs = shapes[s].surface;
    Vec3 c1, c2;
    orthonormal_basis(cs.axis, c1, c2);
    std::array<bool, 36> sectors{};
    for (auto i : shapes[s].inliers) {
      const Vec3 d = in.points[i] - cs.point;
      const double phi = std::atan2(d.dot(c2), d.dot(c1));
      sectors[static_cast<std::size_t>(std::clamp(
          (phi + std::numbers::pi) / (2.0 * std::numbers::pi) * 36.0, 0.0, 35.0))] = true;
    }
    if (10.0 * static_cast<double>(std::count(sectors.begin(), sectors.end(), true)) >=
        in.options->min_angular_span_deg) {
      curved.push_back(static_cast<int>(s));
    }
  }
  std::vector<char> grouped(shapes.size(), 0);
  for (int lead : curved) {
    if (grouped[static_cast<std::size_t>(lead)]) continue;
    const Surface& ls = shapes[static_cast<std::size_t>(lead)].surface;
    const Vec3 axis = canonical_axis(ls.axis);
    const Vec3 origin = ls.point;
    auto on_axis = [&](const Vec3& p) {
      const Vec3 d = p - origin;
      return (d - d.dot(axis) * axis).norm() <= near_axis;
    };
    std::vector<int> group{lead};
    for (int other : curved) {
      if (other == lead || grouped[static_cast<std::size_t>(other)]) continue;
      const Surface& os = shapes[static_cast<std::size_t>(other)].surface;
      if (std::abs(os.axis.dot(axis)) < std::cos(tol) || !on_axis(os.point)) continue;
      group.push_back(other);
    }
    if (group.size() < 2) continue;
    std::sort(group.begin(), group.end());
    Vec3 e1, e2;
    orthonormal_basis(axis, e1, e2);
    auto rho_z = [&](const Vec3& p) {
      const Vec3 d = p - origin;
      const double z = d.dot(axis);
      return Vec2((d - z * axis).norm(), z);
    };
    // Pieces of one surface found twice (equal radius, or equal cone) are one piece.
    std::vector<int> distinct;
    std::vector<std::size_t> rep(group.size());  // index into distinct
    for (std::size_t gi = 0; gi < group.size(); ++gi) {
      const Surface& s = shapes[static_cast<std::size_t>(group[gi])].surface;
      rep[gi] = distinct.size();
      for (std::size_t k = 0; k < distinct.size(); ++k) {
        const Surface& o = shapes[static_cast<std::size_t>(distinct[k])].surface;
        if (s.type != o.type) continue;
        const bool same =
            (s.type == ShapeType::Cylinder && std::abs(s.radius - o.radius) <= 3.0 * eps) ||
            (s.type == ShapeType::Cone && std::abs(s.angle - o.angle) <= tol &&
             std::abs((s.point - o.point).dot(axis)) <= near_axis);
        if (same) {
          rep[gi] = k;
          break;
        }
      }
      if (rep[gi] == distinct.size()) distinct.push_back(group[gi]);
    }
    if (distinct.size() < 2) continue;
    std::vector<ProfileSegment> segments;
    double rho_max = 0.0;
    std::array<bool, 72> sector{};
    std::vector<std::uint32_t> members;
    auto take = [&](const DetectedShape& shape) {
      for (auto i : shape.inliers) {
        if (!(*in.used)[i]) members.push_back(i);
      }
    };
    std::vector<std::pair<double, double>> z_range(distinct.size(), {INFINITY, -INFINITY});
    for (std::size_t gi = 0; gi < group.size(); ++gi) {
      const DetectedShape& shape = shapes[static_cast<std::size_t>(group[gi])];
      double& z0 = z_range[rep[gi]].first;
      double& z1 = z_range[rep[gi]].second;
      for (auto i : shape.inliers) {
        const Vec2 rz = rho_z(in.points[i]);
        z0 = std::min(z0, rz.y());
        z1 = std::max(z1, rz.y());
        const Vec3 d = in.points[i] - origin;
        const double phi = std::atan2(d.dot(e2), d.dot(e1));
        sector[static_cast<std::size_t>(std::clamp(
            (phi + std::numbers::pi) / (2.0 * std::numbers::pi) * 72.0, 0.0, 71.0))] = true;
      }
      take(shape);
    }
    for (std::size_t k = 0; k < distinct.size(); ++k) {
      const Surface& s = shapes[static_cast<std::size_t>(distinct[k])].surface;
      if (s.type == ShapeType::Torus) {
        // The seen arc of the tube's circle, as four chords: angles θ about the tube centre
        // measured from the inliers' mean direction (an arc of less than a full turn).
        const Vec2 centre(s.radius, (s.point - origin).dot(axis));
        Vec2 mean = Vec2::Zero();
        const auto& inl = shapes[static_cast<std::size_t>(distinct[k])].inliers;
        for (auto i : inl) mean += (rho_z(in.points[i]) - centre).normalized();
        if (mean.norm() <= 0.0) continue;
        const double ref = std::atan2(mean.y(), mean.x());
        double lo = INFINITY, hi = -INFINITY;
        for (auto i : inl) {
          const Vec2 q = rho_z(in.points[i]) - centre;
          double th = std::atan2(q.y(), q.x()) - ref;
          th = std::remainder(th, 2.0 * std::numbers::pi);
          lo = std::min(lo, th);
          hi = std::max(hi, th);
        }
        constexpr int kChords = 4;
        for (int c = 0; c < kChords; ++c) {
          const double a0 = ref + lo + (hi - lo) * c / kChords;
          const double a1 = ref + lo + (hi - lo) * (c + 1) / kChords;
          const Vec2 p0 = centre + s.radius2 * Vec2(std::cos(a0), std::sin(a0));
          const Vec2 p1 = centre + s.radius2 * Vec2(std::cos(a1), std::sin(a1));
          segments.push_back({p0, p1});
          rho_max = std::max({rho_max, p0.x(), p1.x()});
        }
        continue;
      }
      auto rho_at = [&](double z) {
        if (s.type == ShapeType::Cylinder) return s.radius;
        const double apex = (s.point - origin).dot(axis);
        return std::abs(z - apex) * std::tan(s.angle);
      };
      const auto [z0, z1] = z_range[k];
      segments.push_back({Vec2(rho_at(z0), z0), Vec2(rho_at(z1), z1)});
      rho_max = std::max({rho_max, rho_at(z0), rho_at(z1)});
    }
    // Planes ⟂ the axis within the group's radius: the discs and rings of the profile.
    std::vector<int> absorbed = group;
    for (std::size_t s = 0; s < shapes.size(); ++s) {
      const Surface& ps = shapes[s].surface;
      if (ps.type != ShapeType::Plane || (*in.absorbed)[s] || grouped[s] ||
          std::abs(ps.axis.dot(axis)) < std::cos(tol)) {
        continue;
      }
      double r0 = INFINITY, r1 = -INFINITY, zs = 0.0;
      std::size_t within = 0;
      for (auto i : shapes[s].inliers) {
        const Vec2 rz = rho_z(in.points[i]);
        if (rz.x() > rho_max + 2.0 * near_axis) continue;
        ++within;
        r0 = std::min(r0, rz.x());
        r1 = std::max(r1, rz.x());
        zs += rz.y();
      }
      if (within * 10 < shapes[s].inliers.size() * 8 || within == 0) continue;
      zs /= static_cast<double>(within);
      segments.push_back({Vec2(r0, zs), Vec2(r1, zs)});
      absorbed.push_back(static_cast<int>(s));
      take(shapes[s]);
    }
    // Angular span: the largest run of empty 5° sectors is where the turn is open.
    const auto seen = std::count(sector.begin(), sector.end(), true);
    const bool full = seen >= 66;
    double zmin = INFINITY, zmax = -INFINITY;
    for (const auto& sg : segments) {
      zmin = std::min({zmin, sg.a.y(), sg.b.y()});
      zmax = std::max({zmax, sg.a.y(), sg.b.y()});
    }
    if (full) segments.push_back({Vec2(0.0, zmax), Vec2(0.0, zmin)});
    auto rings = chain_profile(segments, std::max(4.0 * near_axis, 0.1 * (zmax - zmin)));
    const std::string what = "revolution of " + std::to_string(group.size()) +
                             " coaxial shapes from " + std::string(shape_type_name(ls.type)) + " " +
                             std::to_string(lead);
    if (rings.empty()) {
      rejected.push_back(
          {what, "no closed profile from its pieces", static_cast<long long>(members.size())});
      continue;
    }
    std::size_t best = 0;
    for (std::size_t r = 1; r < rings.size(); ++r) {
      if (std::abs(ring_area(rings[r])) > std::abs(ring_area(rings[best]))) best = r;
    }
    std::vector<Vec2> profile = rings[best];
    for (auto& p : profile) p.x() = std::max(0.0, p.x());
    if (full && profile.size() <= 4) {
      // A plain cylinder or frustum: the simpler primitive stays (curved shapes' own).
      continue;
    }
    if (ring_area(profile) < 0.0) std::reverse(profile.begin(), profile.end());
    double start = 0.0, angle = 2.0 * std::numbers::pi;
    if (!full) {
      // Open where the empty sectors run longest; the span from the inliers' own angles.
      std::size_t run_start = 0, run_best = 0;
      for (std::size_t k = 0; k < 72; ++k) {
        if (sector[k]) continue;
        std::size_t len = 0;
        while (len < 72 && !sector[(k + len) % 72]) ++len;
        if (len > run_best) {
          run_best = len;
          run_start = k;
        }
      }
      const double gap0 =
          -std::numbers::pi + static_cast<double>(run_start) * 2.0 * std::numbers::pi / 72.0;
      double lo = INFINITY, hi = -INFINITY;
      for (int g : group) {
        for (auto i : shapes[static_cast<std::size_t>(g)].inliers) {
          const Vec3 d = in.points[i] - origin;
          double rel = std::atan2(d.dot(e2), d.dot(e1)) - gap0;
          rel = std::fmod(rel + 4.0 * std::numbers::pi, 2.0 * std::numbers::pi);
          lo = std::min(lo, rel);
          hi = std::max(hi, rel);
        }
      }
      start = gap0 + lo;
      angle = std::clamp(hi - lo, 1e-3, 2.0 * std::numbers::pi);
    }
    const Vec3 x = std::cos(start) * e1 + std::sin(start) * e2;
    auto loc = place(frame_of(x.normalized(), axis), origin);
    if (!loc) continue;
    Proposal p;
    p.spec.type = PrimitiveType::Revolution;
    p.spec.profile = profile;
    p.spec.angle = angle;
    p.spec.placement = *loc;
    std::sort(members.begin(), members.end());
    members.erase(std::unique(members.begin(), members.end()), members.end());
    p.members = std::move(members);
    // Area of the revolved profile (Pappus): edge length × 2π·ρ of its midpoint × angle/2π.
    for (std::size_t k = 0; k < profile.size(); ++k) {
      const Vec2& a = profile[k];
      const Vec2& b = profile[(k + 1) % profile.size()];
      p.area += (b - a).norm() * 0.5 * (a.x() + b.x()) * angle;
    }
    std::sort(absorbed.begin(), absorbed.end());
    p.shapes = absorbed;
    p.what = what;
    for (int g : absorbed) grouped[static_cast<std::size_t>(g)] = 1;
    out.push_back(std::move(p));
  }
  return out;
}

std::optional<Proposal> propose_extrusion(const ProposalInput& in,
                                          std::vector<Rejection>& rejected) {
  const auto& shapes = in.shapes->shapes;
  const double tol = deg(in.options->angle_tolerance_deg);
  const double eps = in.ransac->epsilon;
  const double tight = 2.0 * eps;
  std::vector<int> planes;
  for (std::size_t s = 0; s < shapes.size(); ++s) {
    if (shapes[s].surface.type == ShapeType::Plane && !(*in.absorbed)[s] &&
        static_cast<long long>(shapes[s].inliers.size()) >= in.ransac->min_points) {
      planes.push_back(static_cast<int>(s));
    }
  }
  if (planes.size() < 3) return std::nullopt;
  std::stable_sort(planes.begin(), planes.end(), [&](int a, int b) {
    return shapes[static_cast<std::size_t>(a)].inliers.size() >
           shapes[static_cast<std::size_t>(b)].inliers.size();
  });
  if (planes.size() > 24) planes.resize(24);
  auto normal_of = [&](int s) { return shapes[static_cast<std::size_t>(s)].surface.axis; };
  // Candidate directions: vertical, and the lines where two large planes meet.
  std::vector<Vec3> directions{Vec3::UnitZ()};
  const std::size_t pair_limit = std::min<std::size_t>(planes.size(), 8);
  for (std::size_t i = 0; i < pair_limit; ++i) {
    for (std::size_t j = i + 1; j < pair_limit; ++j) {
      const Vec3 c = normal_of(planes[i]).cross(normal_of(planes[j]));
      if (c.norm() < std::sin(deg(20.0))) continue;
      const Vec3 d = canonical_axis(c.normalized());
      bool known = false;
      for (const auto& k : directions) known = known || std::abs(k.dot(d)) >= std::cos(tol);
      if (!known) directions.push_back(d);
    }
  }
  // Score: the inliers of the planes parallel to the direction, with at least three of them
  // facing two or more ways.
  struct Choice {
    Vec3 d;
    long long score = 0;
  };
  std::vector<Choice> choices;
  for (const auto& d : directions) {
    long long score = 0;
    int sides = 0;
    std::vector<Vec3> facings;
    for (int s : planes) {
      const Vec3 n = normal_of(s);
      if (std::abs(n.dot(d)) > std::sin(tol)) continue;
      ++sides;
      score += static_cast<long long>(shapes[static_cast<std::size_t>(s)].inliers.size());
      bool known = false;
      for (const auto& f : facings) known = known || std::abs(f.dot(n)) >= std::cos(tol);
      if (!known) facings.push_back(n);
    }
    if (sides >= 3 && facings.size() >= 2) choices.push_back({d, score});
  }
  std::stable_sort(choices.begin(), choices.end(),
                   [](const Choice& a, const Choice& b) { return a.score > b.score; });
  if (choices.empty()) {
    rejected.push_back({"extrusion", "no three planes parallel to one direction", 0});
    return std::nullopt;
  }
  long long region_points = 0;
  for (std::size_t i = 0; i < in.points.size(); ++i) {
    region_points += (!(*in.used)[i] && in.points[i].allFinite()) ? 1 : 0;
  }
  const double lambda = 0.5 * std::log2(std::max<double>(2.0, static_cast<double>(region_points)));
  std::string last_reason;
  long long last_points = 0;
  for (std::size_t c = 0; c < std::min<std::size_t>(choices.size(), 3); ++c) {
    const Vec3 d = choices[c].d;
    Vec3 e1, e2;
    orthonormal_basis(d, e1, e2);
    const Vec3 origin = shapes[static_cast<std::size_t>(planes[0])].surface.point;
    auto section = [&](const Vec3& p) {
      const Vec3 q = p - origin;
      return std::pair<Vec2, double>(Vec2(q.dot(e1), q.dot(e2)), q.dot(d));
    };
    // Side traces (runs along each wall's line) with their extent along d; caps.
    struct Trace {
      int shape;
      ProfileSegment seg;
      double t0, t1;
      long long points;
    };
    std::vector<Trace> traces;
    std::vector<int> caps;
    double t_lo = INFINITY, t_hi = -INFINITY;
    for (int s : planes) {
      const Surface& ps = shapes[static_cast<std::size_t>(s)].surface;
      const auto& inl = shapes[static_cast<std::size_t>(s)].inliers;
      if (std::abs(ps.axis.dot(d)) >= std::cos(tol)) {
        caps.push_back(s);
        continue;
      }
      if (std::abs(ps.axis.dot(d)) > std::sin(tol)) continue;
      Vec2 n2(ps.axis.dot(e1), ps.axis.dot(e2));
      n2.normalize();
      const Vec2 along(-n2.y(), n2.x());
      const double offset = section(ps.point).first.dot(n2);
      std::vector<double> s_values;
      double t0 = INFINITY, t1 = -INFINITY;
      for (auto i : inl) {
        const auto [q, t] = section(in.points[i]);
        s_values.push_back(q.dot(along));
        t0 = std::min(t0, t);
        t1 = std::max(t1, t);
      }
      for (const auto& [s0, s1] :
           runs(s_values, std::max(4.0 * in.cell, 0.5),
                static_cast<std::size_t>(std::max<long long>(3, in.ransac->min_points / 4)))) {
        traces.push_back({s,
                          {offset * n2 + s0 * along, offset * n2 + s1 * along},
                          t0,
                          t1,
                          static_cast<long long>(inl.size())});
      }
      t_lo = std::min(t_lo, t0);
      t_hi = std::max(t_hi, t1);
    }
    // Walls of one prism share its extent along d: traces covering less than half of it
    // belong to something else.
    std::vector<ProfileSegment> segments;
    std::vector<int> absorbed;
    double t0 = INFINITY, t1 = -INFINITY;
    for (const auto& tr : traces) {
      if (tr.t1 - tr.t0 < 0.5 * (t_hi - t_lo)) continue;
      segments.push_back(tr.seg);
      absorbed.push_back(tr.shape);
      t0 = std::min(t0, tr.t0);
      t1 = std::max(t1, tr.t1);
    }
    if (segments.size() < 3) {
      last_reason = "fewer than three walls share one extent along the direction";
      continue;
    }
    double extent = 0.0;
    for (const auto& sg : segments) extent = std::max(extent, (sg.b - sg.a).norm());
    auto rings = chain_profile(segments, std::max(8.0 * tight, 0.25 * extent));
    if (rings.empty()) {
      last_reason = "its walls close no profile";
      continue;
    }
    std::size_t best = 0;
    for (std::size_t r = 1; r < rings.size(); ++r) {
      if (std::abs(ring_area(rings[r])) > std::abs(ring_area(rings[best]))) best = r;
    }
    Prism prism;
    prism.outer = rings[best];
    if (ring_area(prism.outer) < 0.0) std::reverse(prism.outer.begin(), prism.outer.end());
    for (std::size_t r = 0; r < rings.size(); ++r) {
      if (r == best) continue;
      bool inside = true;
      for (const auto& p : rings[r]) inside = inside && inside_ring(p, prism.outer);
      if (!inside) continue;
      auto hole = rings[r];
      if (ring_area(hole) > 0.0) std::reverse(hole.begin(), hole.end());
      prism.holes.push_back(std::move(hole));
    }
    // Caps: planes ⟂ d over the profile set the extent; a vertical prism reaches the ground.
    // A cap partly over the profile and partly beside it says the walls were chained wrongly
    // (walls of a courtyard joined to outer walls, a wall missing).
    bool cut = false;
    for (int s : caps) {
      const auto& inl = shapes[static_cast<std::size_t>(s)].inliers;
      std::size_t over = 0;
      double mean = 0.0;
      for (auto i : inl) {
        const auto [q, t] = section(in.points[i]);
        if (inside_polygon(q, prism.outer, prism.holes) ||
            Prism{prism.outer, prism.holes, 1.0}.distance(q, 0.5) <= 2.0 * tight) {
          ++over;
          mean += t;
        }
      }
      if (over * 10 < inl.size() * 8) {
        if (over * 10 >= inl.size() * 2) {
          cut = true;
          last_reason = "its profile cuts through plane " + std::to_string(s) + " across it";
          last_points = static_cast<long long>(inl.size());
        }
        continue;
      }
      mean /= static_cast<double>(over);
      if (mean < t0 - 4.0 * tight || mean > t1 + 4.0 * tight) continue;
      t0 = std::min(t0, mean);
      t1 = std::max(t1, mean);
      absorbed.push_back(s);
    }
    if (cut) continue;
    if (in.options->ground != nullptr && std::abs(d.z()) >= std::cos(tol)) {
      Vec2 centre = Vec2::Zero();
      double radius = 0.0;
      for (const auto& p : prism.outer) centre += p / static_cast<double>(prism.outer.size());
      for (const auto& p : prism.outer) radius = std::max(radius, (p - centre).norm());
      const Vec3 w = origin + centre.x() * e1 + centre.y() * e2;
      const double g = in.options->ground->median_near(w.x(), w.y(), radius);
      if (std::isfinite(g)) t0 = std::min(t0, (g - origin.z()) / d.z());
    }
    prism.h = t1 - t0;
    if (!(prism.h > in.options->min_box_thickness)) {
      last_reason = "no height along the direction";
      continue;
    }
    // The box: the smallest rectangle with a side along an edge of the profile (enough for
    // the profiles here, which are near-convex or have their extreme edges seen).
    const auto rectangle = smallest_rectangle(prism.outer, 1e-12);
    Prism box{rectangle ? rectangle->corners() : std::vector<Vec2>{}, {}, prism.h};
    std::vector<std::uint32_t> members;
    long long box_points = 0;
    for (std::uint32_t i = 0; i < in.points.size(); ++i) {
      if ((*in.used)[i] || !in.points[i].allFinite()) continue;
      const auto [q, t] = section(in.points[i]);
      if (prism.distance(q, t - t0) <= tight) members.push_back(i);
      if (box.distance(q, t - t0) <= tight) ++box_points;
    }
    std::size_t vertices = prism.outer.size();
    for (const auto& h : prism.holes) vertices += h.size();
    const double dl_extrusion =
        static_cast<double>(region_points - static_cast<long long>(members.size())) +
        lambda * static_cast<double>(2 * vertices + 7);
    const double dl_box = static_cast<double>(region_points - box_points) + lambda * 9.0;
    if (!(dl_extrusion < dl_box)) {
      last_reason = "the box around its profile describes the points as well (description length " +
                    std::to_string(static_cast<long long>(dl_box)) +
                    " <= " + std::to_string(static_cast<long long>(dl_extrusion)) + ")";
      last_points = static_cast<long long>(members.size());
      continue;
    }
    auto loc = place(frame_of(e1.normalized(), d), origin + t0 * d);
    if (!loc) continue;
    Proposal p;
    p.spec.type = PrimitiveType::Extrusion;
    p.spec.profile = prism.outer;
    p.spec.holes = prism.holes;
    p.spec.height = prism.h;
    p.spec.placement = *loc;
    p.members = std::move(members);
    p.area = 2.0 * polygon_area(prism.outer, prism.holes) +
             polygon_perimeter(prism.outer, prism.holes) * prism.h;
    std::sort(absorbed.begin(), absorbed.end());
    absorbed.erase(std::unique(absorbed.begin(), absorbed.end()), absorbed.end());
    p.shapes = absorbed;
    p.what = "extrusion of " + std::to_string(segments.size()) + " walls";
    return p;
  }
  if (!last_reason.empty()) rejected.push_back({"extrusion", last_reason, last_points});
  return std::nullopt;
}

}  // namespace csgtile::fit::detail
