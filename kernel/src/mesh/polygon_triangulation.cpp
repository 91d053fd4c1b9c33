#include "mesh/polygon_triangulation.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace csgtile::kernel::detail {

namespace {

// Twice the signed area of (a, b, c): positive when counter-clockwise.
double orient(const Vec2& a, const Vec2& b, const Vec2& c) {
  return (b.x() - a.x()) * (c.y() - a.y()) - (b.y() - a.y()) * (c.x() - a.x());
}

double cross(const Vec2& a, const Vec2& b) { return a.x() * b.y() - a.y() * b.x(); }

struct Node {
  Vec2 p;
  std::uint32_t index;
  int prev = -1;
  int next = -1;
};

// One polygon as a circular doubly linked list. Holes are spliced into the outer ring by
// bridges (two coincident copies of each bridge end), giving one weakly simple ring that is
// then clipped ear by ear.
class EarClipper {
 public:
  explicit EarClipper(const std::vector<std::vector<Vec2>>& loops) {
    std::uint32_t first_index = 0;
    for (std::size_t l = 0; l < loops.size(); ++l) {
      const int start = add_loop(loops[l], first_index, /*counter_clockwise=*/l == 0);
      first_index += static_cast<std::uint32_t>(loops[l].size());
      if (l == 0) {
        outer_ = start;
      } else if (start >= 0) {
        holes_.push_back(start);
      } else if (!loops[l].empty()) {
        result_.complete = false;  // a hole without area cannot be meshed around
      }
    }
  }

  PolygonTriangulation run() {
    if (outer_ < 0) {
      result_.complete = false;
      return std::move(result_);
    }
    eliminate_holes();
    clip_ears();
    return std::move(result_);
  }

 private:
  // Links the loop's points (consecutive exact duplicates dropped) in the wanted direction;
  // returns a node of the ring, or -1 when fewer than three points remain.
  int add_loop(const std::vector<Vec2>& loop, std::uint32_t first_index, bool counter_clockwise) {
    std::vector<int> ring;
    for (std::size_t i = 0; i < loop.size(); ++i) {
      if (!ring.empty() && nodes_[static_cast<std::size_t>(ring.back())].p == loop[i]) continue;
      nodes_.push_back({loop[i], first_index + static_cast<std::uint32_t>(i)});
      ring.push_back(static_cast<int>(nodes_.size() - 1));
    }
    while (ring.size() > 1 && nodes_[static_cast<std::size_t>(ring.back())].p ==
                                  nodes_[static_cast<std::size_t>(ring.front())].p) {
      ring.pop_back();
    }
    if (ring.size() < 3) return -1;
    double area2 = 0.0;
    for (std::size_t i = 0; i < ring.size(); ++i) {
      area2 += cross(node(ring[i]).p, node(ring[(i + 1) % ring.size()]).p);
    }
    if ((area2 > 0) != counter_clockwise) std::reverse(ring.begin(), ring.end());
    for (std::size_t i = 0; i < ring.size(); ++i) {
      node(ring[i]).next = ring[(i + 1) % ring.size()];
      node(ring[(i + 1) % ring.size()]).prev = ring[i];
    }
    return ring.front();
  }

  Node& node(int i) { return nodes_[static_cast<std::size_t>(i)]; }
  const Node& node(int i) const { return nodes_[static_cast<std::size_t>(i)]; }

  // Holes in decreasing order of their rightmost x: a hole's bridge then never crosses a
  // hole that is not merged yet (those lie entirely to its left).
  void eliminate_holes() {
    std::vector<std::pair<int, int>> order;  // (rightmost node, hole position)
    for (std::size_t h = 0; h < holes_.size(); ++h) {
      int best = holes_[h];
      int n = node(best).next;
      while (n != holes_[h]) {
        const Vec2& p = node(n).p;
        const Vec2& q = node(best).p;
        if (p.x() > q.x() || (p.x() == q.x() && p.y() < q.y())) best = n;
        n = node(n).next;
      }
      order.emplace_back(best, static_cast<int>(h));
    }
    std::sort(order.begin(), order.end(), [&](const auto& a, const auto& b) {
      const Vec2& p = node(a.first).p;
      const Vec2& q = node(b.first).p;
      if (p.x() != q.x()) return p.x() > q.x();
      if (p.y() != q.y()) return p.y() < q.y();
      return a.second < b.second;
    });
    for (const auto& [m, h] : order) {
      if (!bridge(m)) result_.complete = false;
    }
  }

  // Connects hole node m to a visible node of the outer ring (Eberly's ray method: cast a
  // ray towards +x, take the nearest crossed edge's right end, and if outer vertices lie in
  // the triangle between m, the hit and that end, the one closest in angle to the ray).
  bool bridge(int m) {
    const Vec2 mp = node(m).p;
    double best_x = std::numeric_limits<double>::infinity();
    int edge = -1;
    int n = outer_;
    do {
      const Vec2& a = node(n).p;
      const Vec2& b = node(node(n).next).p;
      if (a.y() != b.y() &&
          ((a.y() <= mp.y() && mp.y() <= b.y()) || (b.y() <= mp.y() && mp.y() <= a.y()))) {
        const double x = a.x() + (mp.y() - a.y()) * (b.x() - a.x()) / (b.y() - a.y());
        if (x >= mp.x() && x < best_x) {
          best_x = x;
          edge = n;
        }
      }
      n = node(n).next;
    } while (n != outer_);
    if (edge < 0) return false;
    const Vec2 hit(best_x, mp.y());
    int p = edge;
    const int q = node(edge).next;
    if (node(q).p == hit || (node(p).p != hit && node(q).p.x() > node(p).p.x())) p = q;
    if (node(p).p != hit) {
      // Outer vertices inside triangle (m, hit, p) could hide p; the one at the smallest
      // angle from the ray is visible.
      const Vec2 pp = node(p).p;
      const double sense = orient(mp, hit, pp) >= 0 ? 1.0 : -1.0;
      double best_tan = std::numeric_limits<double>::infinity(), best_dx = best_tan;
      n = outer_;
      do {
        const Vec2& r = node(n).p;
        if (r != pp && r.x() >= mp.x() && sense * orient(mp, hit, r) >= 0 &&
            sense * orient(hit, pp, r) >= 0 && sense * orient(pp, mp, r) >= 0) {
          const double dx = r.x() - mp.x();
          const double tan =
              dx > 0 ? std::abs(r.y() - mp.y()) / dx : std::numeric_limits<double>::infinity();
          if (tan < best_tan || (tan == best_tan && dx < best_dx)) {
            best_tan = tan;
            best_dx = dx;
            p = n;
          }
        }
        n = node(n).next;
      } while (n != outer_);
    }
    p = pick_copy(p, mp);
    splice(p, m);
    return true;
  }

  // Among coincident copies of a node (ends of earlier bridges), the one whose interior
  // wedge contains the direction towards `target`.
  int pick_copy(int p, const Vec2& target) const {
    const Vec2 pos = node(p).p;
    int n = outer_;
    do {
      if (node(n).p == pos && wedge_contains(n, target)) return n;
      n = node(n).next;
    } while (n != outer_);
    return p;
  }

  bool wedge_contains(int n, const Vec2& target) const {
    const Vec2& v = node(n).p;
    const Vec2 to_next = node(node(n).next).p - v;
    const Vec2 to_prev = node(node(n).prev).p - v;
    const Vec2 d = target - v;
    // The interior lies counter-clockwise from to_next to to_prev.
    if (cross(to_next, to_prev) > 0) return cross(to_next, d) > 0 && cross(d, to_prev) > 0;
    return !(cross(to_prev, d) >= 0 && cross(d, to_next) >= 0);
  }

  void splice(int p, int m) {
    const int p_copy = static_cast<int>(nodes_.size());
    nodes_.push_back(node(p));
    const int m_copy = static_cast<int>(nodes_.size());
    nodes_.push_back(node(m));
    const int m_prev = node(m).prev;
    const int p_next = node(p).next;
    node(p).next = m;
    node(m).prev = p;
    node(m_prev).next = m_copy;
    node(m_copy).prev = m_prev;
    node(m_copy).next = p_copy;
    node(p_copy).prev = m_copy;
    node(p_copy).next = p_next;
    node(p_next).prev = p_copy;
  }

  // Strictly convex at b, and no other ring point inside, on or within rounding of the
  // triangle except copies of its corners (bridge ends): a point on the new diagonal would
  // become a T-junction. Points collinear in exact arithmetic (a wall's corners along one
  // line, in a face's rotated parameter plane) lie a few ulps off the diagonal; taking them
  // for outside would leave the last three points collinear, so points within a billionth
  // of the triangle's size of its sides count as on them.
  bool is_ear(int a, int b, int c) const {
    const Vec2& pa = node(a).p;
    const Vec2& pb = node(b).p;
    const Vec2& pc = node(c).p;
    const double ab = (pb - pa).norm(), bc = (pc - pb).norm(), ca = (pa - pc).norm();
    const double area2 = orient(pa, pb, pc);
    if (!(area2 > 1e-12 * ab * bc)) return false;
    const double slack = 1e-9 * std::max({ab, bc, ca});
    const double min_x = std::min({pa.x(), pb.x(), pc.x()}) - slack;
    const double max_x = std::max({pa.x(), pb.x(), pc.x()}) + slack;
    const double min_y = std::min({pa.y(), pb.y(), pc.y()}) - slack;
    const double max_y = std::max({pa.y(), pb.y(), pc.y()}) + slack;
    for (int n = node(c).next; n != a; n = node(n).next) {
      const Vec2& p = node(n).p;
      if (p.x() < min_x || p.x() > max_x || p.y() < min_y || p.y() > max_y) continue;
      if (p == pa || p == pb || p == pc) continue;
      // orient(u, v, p) / |v - u| is p's signed distance from the line u v.
      if (orient(pa, pb, p) >= -slack * ab && orient(pb, pc, p) >= -slack * bc &&
          orient(pc, pa, p) >= -slack * ca) {
        return false;
      }
    }
    return true;
  }

  void emit(int a, int b, int c) {
    result_.triangles.push_back({node(a).index, node(b).index, node(c).index});
  }

  void unlink(int b) {
    const int a = node(b).prev, c = node(b).next;
    node(a).next = c;
    node(c).prev = a;
  }

  void clip_ears() {
    int count = 0;
    int n = outer_;
    do {
      ++count;
      n = node(n).next;
    } while (n != outer_);
    int current = outer_;
    int stalled = 0;
    while (count > 3) {
      const int a = node(current).prev, c = node(current).next;
      if (is_ear(a, current, c)) {
        emit(a, current, c);
        unlink(current);
        --count;
        stalled = 0;
        // Continuing two steps on spreads the ears around the ring (fewer long fans).
        current = node(c).next;
        continue;
      }
      current = c;
      if (++stalled < count) continue;
      // No clean ear: rounding or an overlapping input. Clip the widest convex corner so the
      // result still matches the boundary edge for edge.
      int best = -1;
      double best_area = 0.0;
      n = current;
      do {
        const double area2 = orient(node(node(n).prev).p, node(n).p, node(node(n).next).p);
        if (area2 > best_area) {
          best_area = area2;
          best = n;
        }
        n = node(n).next;
      } while (n != current);
      if (best < 0) {
        result_.complete = false;  // what is left has no area
        return;
      }
      emit(node(best).prev, best, node(best).next);
      current = node(best).next;
      unlink(best);
      --count;
      stalled = 0;
    }
    const int a = node(current).prev, c = node(current).next;
    const double area2 = orient(node(a).p, node(current).p, node(c).p);
    if (area2 > 0) {
      emit(a, current, c);
    } else {
      result_.complete = false;
    }
  }

  std::vector<Node> nodes_;
  int outer_ = -1;
  std::vector<int> holes_;
  PolygonTriangulation result_;
};

}  // namespace

PolygonTriangulation triangulate_polygon(const std::vector<std::vector<Vec2>>& loops) {
  if (loops.empty()) return {{}, false};
  PolygonTriangulation first = EarClipper(loops).run();
  if (first.complete) return first;
  // Bridges are cast along +x: where holes' edges and an outer vertex lie on one horizontal
  // line to within a few ulps (faces of buildings built on a grid), a bridge runs along a
  // hole's edge and every ear left has a bridge end on its diagonal. The same loops in a
  // turned frame have no such near-ties; a rotation keeps the points, their order and every
  // triangle's orientation. Deterministic: the first frame that meshes wins.
  for (const double angle : {0.3, 1.1}) {
    const double c = std::cos(angle), s = std::sin(angle);
    std::vector<std::vector<Vec2>> turned(loops.size());
    for (std::size_t l = 0; l < loops.size(); ++l) {
      for (const Vec2& p : loops[l]) {
        turned[l].emplace_back(c * p.x() - s * p.y(), s * p.x() + c * p.y());
      }
    }
    PolygonTriangulation again = EarClipper(turned).run();
    if (again.complete) return again;
  }
  return first;
}

}  // namespace csgtile::kernel::detail
