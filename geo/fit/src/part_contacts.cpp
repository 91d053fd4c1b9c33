// Point contacts between the parts of a roof partition (part_contacts.h).

#include "part_contacts.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <utility>

#include "csgtile/kernel/polygon2d.h"

namespace csgtile::fit::detail {

namespace {

using Key = std::pair<long long, long long>;
using kernel::Vec2;

// A vertex's place, to a micrometre (the parts' shared vertices are snapped to one point).
Key key_of(const Vec3& w) { return {std::llround(w.x() * 1e6), std::llround(w.y() * 1e6)}; }

// One part's ring through a vertex: the part and the places of the ring's vertices before
// and after it.
struct Incidence {
  std::size_t part = 0;
  Key prev, next;
  int ring = -1;          // -1: the outer ring, else the hole's index
  std::size_t index = 0;  // the vertex's index in that ring
};

// An extrusion standing upright: its placement turns about z only.
bool upright_extrusion(const kernel::PrimitiveSpec& s) {
  if (s.type != kernel::PrimitiveType::Extrusion) return false;
  const auto& r = s.placement.rotation();
  return s.placement.scale() == 1.0 && std::abs(r(2, 2) - 1.0) < 1e-12;
}

double base_of(const kernel::PrimitiveSpec& s) { return s.placement.translation().z(); }

// The part's roof over the world point (x, y): its top, or lower where a clip plane cuts it.
double roof_at(const kernel::PrimitiveSpec& s, double x, double y) {
  const auto& r = s.placement.rotation();
  const Vec3 t = s.placement.translation();
  double top = t.z() + s.height;
  for (const Eigen::Vector4d& c : s.clips) {
    const Vec3 n = r * Vec3(c.x(), c.y(), c.z());
    const double d = c.w() + n.dot(t);
    if (n.z() > 1e-9) top = std::min(top, (d - n.x() * x - n.y() * y) / n.z());
  }
  return top;
}

// Moves the part's base down by `drop`, its clip planes staying where they are.
void lower_base(kernel::PrimitiveSpec& s, double drop) {
  const auto& r = s.placement.rotation();
  for (Eigen::Vector4d& c : s.clips) c.w() += drop * (r * Vec3(c.x(), c.y(), c.z())).z();
  s.placement = kernel::Location::translation(Vec3(0.0, 0.0, -drop)) * s.placement;
  s.height += drop;
}

// The part's corner at the incidence's vertex cut off `size` along both its edges (at most a
// quarter of either), when the polygon's inside turns less than half a turn there: the vertex
// becomes two. Returns whether it was cut.
bool cut_corner(kernel::PrimitiveSpec& s, const Incidence& at, double size) {
  std::vector<Vec2>& ring = at.ring < 0 ? s.profile : s.holes[static_cast<std::size_t>(at.ring)];
  const std::size_t n = ring.size();
  const Vec2 v = ring[at.index], prev = ring[(at.index + n - 1) % n],
             next = ring[(at.index + 1) % n];
  const double to_prev = (prev - v).norm(), to_next = (next - v).norm();
  const double e = std::min(size, 0.25 * std::min(to_prev, to_next));
  if (!(e > 0.0)) return false;
  const Vec2 in = v - prev, out = next - v;
  const double turn = in.x() * out.y() - in.y() * out.x();
  // Which side of the ring's edges its polygon lies on: the left of a counter-clockwise outer
  // ring, of a clockwise hole.
  const double left = (at.ring < 0) == (kernel::ring_area(ring) > 0.0) ? 1.0 : -1.0;
  if (!(turn * left > 0.0)) return false;
  ring[at.index] = v + (e / to_prev) * (prev - v);
  ring.insert(ring.begin() + static_cast<std::ptrdiff_t>(at.index) + 1,
              v + (e / to_next) * (next - v));
  return true;
}

}  // namespace

int close_point_contacts(std::vector<Proposal>& parts, double max_raise, double corner) {
  std::set<std::size_t> changed;
  for (int round = 0; round < 8; ++round) {
    std::set<std::size_t> cut;  // parts whose rings changed this round (their incidences stale)
    std::map<Key, std::vector<Incidence>> at;
    for (std::size_t k = 0; k < parts.size(); ++k) {
      const kernel::PrimitiveSpec& s = parts[k].spec;
      if (!upright_extrusion(s)) continue;
      auto add_ring = [&](const std::vector<Vec2>& ring, int which) {
        const std::size_t n = ring.size();
        if (n < 3) return;
        std::vector<Key> keys(n);
        for (std::size_t i = 0; i < n; ++i) {
          keys[i] = key_of(s.placement.apply_point(Vec3(ring[i].x(), ring[i].y(), 0.0)));
        }
        for (std::size_t i = 0; i < n; ++i) {
          at[keys[i]].push_back({k, keys[(i + n - 1) % n], keys[(i + 1) % n], which, i});
        }
      };
      add_ring(s.profile, -1);
      for (std::size_t h = 0; h < s.holes.size(); ++h) add_ring(s.holes[h], static_cast<int>(h));
    }
    bool any = false;
    for (const auto& [place, list] : at) {
      if (list.size() < 3) continue;
      const double x = static_cast<double>(place.first) * 1e-6;
      const double y = static_cast<double>(place.second) * 1e-6;
      for (std::size_t i = 0; i < list.size(); ++i) {
        for (std::size_t j = i + 1; j < list.size(); ++j) {
          const Incidence& a = list[i];
          const Incidence& b = list[j];
          if (a.part == b.part) continue;
          // Parts sharing an edge through the vertex, through any of their passes by it.
          bool share = false;
          for (const Incidence& p : list) {
            if (p.part != a.part) continue;
            for (const Incidence& q : list) {
              if (q.part != b.part) continue;
              share = share || p.prev == q.prev || p.prev == q.next || p.next == q.prev ||
                      p.next == q.next;
            }
          }
          if (share || cut.count(a.part) || cut.count(b.part)) continue;
          const kernel::PrimitiveSpec& sa = parts[a.part].spec;
          const kernel::PrimitiveSpec& sb = parts[b.part].spec;
          const double low = std::max(base_of(sa), base_of(sb));
          const double high = std::min(roof_at(sa, x, y), roof_at(sb, x, y));
          if (!(high > low)) continue;
          bool below = false;  // a part between them standing lower than both, after all
          for (const Incidence& c : list) {
            if (c.part == a.part || c.part == b.part) continue;
            kernel::PrimitiveSpec& sc = parts[c.part].spec;
            if (base_of(sc) > low) {
              lower_base(sc, base_of(sc) - low);
              changed.insert(c.part);
              any = true;
            }
            const double roof = roof_at(sc, x, y);
            if (sc.clips.empty() && roof < high && high - roof <= max_raise) {
              sc.height += high - roof;
              changed.insert(c.part);
              any = true;
            }
            below = below || roof_at(sc, x, y) < high;
          }
          if (!below) continue;
          // A storey lower, or a tilted roof: the corner of one of the two is cut off instead
          // (the lower one at the vertex; a notch of `corner` by `corner`), so that they no
          // longer meet.
          const bool a_first = roof_at(sa, x, y) <= roof_at(sb, x, y);
          for (const Incidence* p : {a_first ? &a : &b, a_first ? &b : &a}) {
            if (cut_corner(parts[p->part].spec, *p, corner)) {
              cut.insert(p->part);
              changed.insert(p->part);
              any = true;
              break;
            }
          }
        }
      }
    }
    if (!any) break;
  }
  return static_cast<int>(changed.size());
}

}  // namespace csgtile::fit::detail
