#include "snap_walls.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>
#include <utility>

#include "csgtile/kernel/polygon2d.h"

namespace csgtile::kernel::detail {

namespace {

using Key = std::pair<long long, long long>;

// Vertices closer than this are one already (their frames' rounding): none moves.
constexpr double kSame = 1e-9;

// A vertex is inserted into an edge only this many snap distances from its ends and from the
// vertices inserted before it: the edges it leaves are no shorter (an 8 mm edge left at a
// corner became a sliver triangle of a LoD1.3 block, crossing its neighbours once the
// published coordinates were rounded to millimetres).
constexpr double kClearance = 4.0;

// A profile vertex seen along its group's direction: its plane coordinates, and its local
// coordinates while it has not moved (an unmoved vertex is written back bit for bit).
struct Corner {
  Vec2 at;
  std::optional<Vec2> local;
};

// An extrusion of a group: its rings (outer first) and its extent along the direction.
struct Walls {
  std::size_t primitive = 0;
  std::vector<std::vector<Corner>> rings;
  double low = 0.0, high = 0.0;
  int moved = 0;
  double max_move = 0.0;
};

// A vertex in the hash: where, and which extrusion of the group it belongs to.
struct Mark {
  Vec2 at;
  std::size_t owner;
};

class Hash {
 public:
  explicit Hash(double distance) : size_(std::max(1.0, distance)) {}
  Key key(const Vec2& q) const {
    return {static_cast<long long>(std::floor(q.x() / size_)),
            static_cast<long long>(std::floor(q.y() / size_))};
  }
  void add(const Vec2& q, std::size_t owner) { cells_[key(q)].push_back({q, owner}); }
  // Every mark in the cells the box lo..hi meets, in a fixed order.
  template <class F>
  void visit(const Vec2& lo, const Vec2& hi, F&& f) const {
    const Key a = key(lo), b = key(hi);
    for (long long x = a.first; x <= b.first; ++x) {
      for (long long y = a.second; y <= b.second; ++y) {
        const auto it = cells_.find({x, y});
        if (it == cells_.end()) continue;
        for (const Mark& m : it->second) f(m);
      }
    }
  }

 private:
  double size_;
  std::map<Key, std::vector<Mark>> cells_;
};

bool heights_meet(const Walls& a, const Walls& b, double distance) {
  return a.low <= b.high + distance && b.low <= a.high + distance;
}

// The ring without repeated neighbours (two vertices merged onto one point).
std::vector<Vec2> without_repeats(const std::vector<Vec2>& ring) {
  std::vector<Vec2> kept;
  for (const Vec2& q : ring) {
    if (kept.empty() || kept.back() != q) kept.push_back(q);
  }
  while (kept.size() > 1 && kept.back() == kept.front()) kept.pop_back();
  return kept;
}

// Whether the rings are still a polygon: each simple and keeping its area's sign (`before`),
// no two meeting.
bool still_valid(const std::vector<std::vector<Vec2>>& before,
                 const std::vector<std::vector<Vec2>>& after) {
  for (std::size_t r = 0; r < after.size(); ++r) {
    const std::vector<Vec2>& ring = after[r];
    if (ring.size() < 3 || ring_self_intersects(ring)) return false;
    const double a0 = ring_area(before[r]), a1 = ring_area(ring);
    if (!(a1 != 0.0) || (a0 > 0.0) != (a1 > 0.0)) return false;
  }
  for (std::size_t r = 0; r < after.size(); ++r) {
    for (std::size_t s = r + 1; s < after.size(); ++s) {
      if (rings_intersect(after[r], after[s])) return false;
    }
  }
  return true;
}

void share_group(std::vector<PrimitiveSpec>& out, const std::vector<std::size_t>& members,
                 const Vec3& w, double distance, SnapReport& counts) {
  const Vec3 x0 = std::abs(w.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
  const Vec3 u = (x0 - x0.dot(w) * w).normalized();
  const Vec3 v = w.cross(u);
  std::vector<Walls> group;
  for (std::size_t i : members) {
    const PrimitiveSpec& p = out[i];
    const Location& at = p.placement;
    Walls walls;
    walls.primitive = i;
    auto seen = [&](const std::vector<Vec2>& ring) {
      std::vector<Corner> corners;
      for (const Vec2& q : ring) {
        const Vec3 world = at.apply_point(Vec3(q.x(), q.y(), 0.0));
        corners.push_back({Vec2(u.dot(world), v.dot(world)), q});
      }
      return corners;
    };
    walls.rings.push_back(seen(p.profile));
    for (const auto& hole : p.holes) walls.rings.push_back(seen(hole));
    const double base = w.dot(at.translation());
    const double top = w.dot(at.apply_point(Vec3(0.0, 0.0, p.height)));
    walls.low = std::min(base, top);
    walls.high = std::max(base, top);
    group.push_back(std::move(walls));
  }
  const Vec2 reach(distance, distance);

  // Vertices onto the nearest vertex of an earlier extrusion within the distance.
  Hash firsts(distance);
  for (std::size_t g = 0; g < group.size(); ++g) {
    Walls& walls = group[g];
    for (auto& ring : walls.rings) {
      for (Corner& c : ring) {
        const Mark* best = nullptr;
        double best_d = distance;
        firsts.visit(c.at - reach, c.at + reach, [&](const Mark& m) {
          if (m.owner == g || !heights_meet(walls, group[m.owner], distance)) return;
          const double d = (m.at - c.at).norm();
          if (d < best_d || (d == best_d && !best)) {
            best = &m;
            best_d = d;
          }
        });
        if (!best) {
          firsts.add(c.at, g);
        } else if (best_d > kSame) {
          c = {best->at, std::nullopt};
          ++walls.moved;
          walls.max_move = std::max(walls.max_move, best_d);
        }
      }
    }
  }

  // Vertices inserted into the other extrusions' edges they lie near, away from the edges' ends
  // (kClearance).
  const double clear = kClearance * distance;
  Hash all(distance);
  for (std::size_t g = 0; g < group.size(); ++g) {
    for (const auto& ring : group[g].rings) {
      for (const Corner& c : ring) all.add(c.at, g);
    }
  }
  for (std::size_t g = 0; g < group.size(); ++g) {
    Walls& walls = group[g];
    for (auto& ring : walls.rings) {
      std::vector<Corner> grown;
      const std::size_t n = ring.size();
      for (std::size_t k = 0; k < n; ++k) {
        const Vec2 a = ring[k].at, b = ring[(k + 1) % n].at;
        grown.push_back(ring[k]);
        const Vec2 d = b - a;
        const double len2 = d.squaredNorm();
        if (!(len2 > 0.0)) continue;
        std::vector<std::pair<double, Vec2>> on;
        all.visit(a.cwiseMin(b) - reach, a.cwiseMax(b) + reach, [&](const Mark& m) {
          if (m.owner == g || !heights_meet(walls, group[m.owner], distance)) return;
          const double t = (m.at - a).dot(d) / len2;
          if (!(t > 0.0 && t < 1.0)) return;
          if ((m.at - a).norm() <= clear || (m.at - b).norm() <= clear) return;
          if ((a + t * d - m.at).norm() > distance) return;
          on.emplace_back(t, m.at);
        });
        std::sort(on.begin(), on.end(), [](const auto& x, const auto& y) {
          if (x.first != y.first) return x.first < y.first;
          return x.second.x() != y.second.x() ? x.second.x() < y.second.x()
                                              : x.second.y() < y.second.y();
        });
        Vec2 last = a;
        for (const auto& [t, q] : on) {
          if ((q - last).norm() <= clear || (q - b).norm() <= clear) continue;
          grown.push_back({q, std::nullopt});
          ++walls.moved;
          walls.max_move = std::max(walls.max_move, segment_distance(q, a, b));
          last = q;
        }
      }
      ring = std::move(grown);
    }
  }

  // Written back where something moved and the rings stay valid.
  for (Walls& walls : group) {
    if (walls.moved == 0) continue;
    PrimitiveSpec& p = out[walls.primitive];
    std::vector<std::vector<Vec2>> before{p.profile};
    before.insert(before.end(), p.holes.begin(), p.holes.end());
    const Location& at = p.placement;
    const Eigen::Matrix3d& r = at.rotation();
    const double base = w.dot(at.translation());
    std::vector<std::vector<Vec2>> after;
    for (const auto& ring : walls.rings) {
      std::vector<Vec2> local;
      for (const Corner& c : ring) {
        if (c.local) {
          local.push_back(*c.local);
          continue;
        }
        const Vec3 world = c.at.x() * u + c.at.y() * v + base * w;
        const Vec3 q = r.transpose() * (world - at.translation()) / at.scale();
        local.emplace_back(q.x(), q.y());
      }
      after.push_back(without_repeats(local));
    }
    if (!still_valid(before, after)) continue;
    p.profile = std::move(after.front());
    p.holes.assign(std::make_move_iterator(after.begin() + 1),
                   std::make_move_iterator(after.end()));
    counts.walls_shared += walls.moved;
    counts.max_move = std::max(counts.max_move, walls.max_move);
  }
}

}  // namespace

void share_extrusion_walls(std::vector<PrimitiveSpec>& primitives, double distance,
                           SnapReport& counts) {
  if (!(distance > 0.0)) return;
  // Groups of extrusions along one direction (either way), in input order.
  std::vector<Vec3> directions;
  std::vector<std::vector<std::size_t>> groups;
  for (std::size_t i = 0; i < primitives.size(); ++i) {
    const PrimitiveSpec& p = primitives[i];
    if (p.type != PrimitiveType::Extrusion || p.profile.size() < 3) continue;
    const Vec3 z = p.placement.rotation().col(2);
    std::size_t g = 0;
    while (g < directions.size() && std::abs(z.dot(directions[g])) < 1.0 - 1e-12) ++g;
    if (g == directions.size()) {
      directions.push_back(z);
      groups.emplace_back();
    }
    groups[g].push_back(i);
  }
  for (std::size_t g = 0; g < groups.size(); ++g) {
    if (groups[g].size() >= 2) share_group(primitives, groups[g], directions[g], distance, counts);
  }
}

}  // namespace csgtile::kernel::detail
