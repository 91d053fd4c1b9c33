// The union of polygons that tile a region edge to edge (footprint_union.h): directed edges of
// counter-clockwise outer rings and clockwise holes, split where another polygon's vertex lies
// on them; an edge and its reverse cancel (two polygons' shared wall); the edges left are the
// union's boundary, walked into rings. Every step that finds the polygons do not tile (an
// edge twice in one direction, a vertex with two ways on, rings that touch) gives up, so that
// the caller keeps the polygons as they are.

#include "footprint_union.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <utility>

#include "csgtile/kernel/polygon2d.h"

namespace csgtile::assembly::detail {

namespace {

using kernel::Vec2;

// Splits above this many edge-vertex tests are not tried (the union is an optimisation).
constexpr double kMaxTests = 4e6;

// Vertices welded within the tolerance: the parts' shared corners come from solids placed
// one by one, so the same corner can differ in its last bits from one part to the next. A
// point takes the id of the first vertex within the tolerance of it (a grid of the
// tolerance's cells, its 3 × 3 block searched), else a new one.
class Vertices {
 public:
  explicit Vertices(double tolerance) : tolerance_(tolerance > 0.0 ? tolerance : 1e-12) {}

  int id(const Vec2& p) {
    const std::int64_t i = cell(p.x()), j = cell(p.y());
    for (std::int64_t di = -1; di <= 1; ++di) {
      for (std::int64_t dj = -1; dj <= 1; ++dj) {
        const auto it = grid_.find({i + di, j + dj});
        if (it == grid_.end()) continue;
        for (const int v : it->second) {
          if ((at(v) - p).norm() <= tolerance_) return v;
        }
      }
    }
    const int v = static_cast<int>(at_.size());
    at_.push_back(p);
    grid_[{i, j}].push_back(v);
    return v;
  }
  const Vec2& at(int i) const { return at_[static_cast<std::size_t>(i)]; }
  std::size_t size() const { return at_.size(); }

 private:
  std::int64_t cell(double x) const {
    return static_cast<std::int64_t>(std::floor(x / tolerance_));
  }

  double tolerance_;
  std::map<std::pair<std::int64_t, std::int64_t>, std::vector<int>> grid_;
  std::vector<Vec2> at_;
};

// The ring without consecutive repeats, turned to the orientation asked for.
std::vector<Vec2> oriented(const std::vector<Vec2>& ring, bool counter_clockwise) {
  std::vector<Vec2> out;
  for (const Vec2& p : ring) {
    if (out.empty() || out.back() != p) out.push_back(p);
  }
  while (out.size() > 1 && out.front() == out.back()) out.pop_back();
  if ((kernel::ring_area(out) > 0.0) != counter_clockwise) std::reverse(out.begin(), out.end());
  return out;
}

// The ring without the vertices within the tolerance of the line through their neighbours
// (where a neighbour's corner met a wall that the union has made one): the walls each side of
// such a vertex would be two faces all but coplanar.
std::vector<Vec2> without_straight_corners(std::vector<Vec2> ring, double tolerance) {
  for (bool removed = true; removed && ring.size() > 3;) {
    removed = false;
    for (std::size_t k = 0; k < ring.size() && ring.size() > 3; ++k) {
      const Vec2& before = ring[(k + ring.size() - 1) % ring.size()];
      const Vec2& after = ring[(k + 1) % ring.size()];
      if (kernel::segment_distance(ring[k], before, after) <= tolerance) {
        ring.erase(ring.begin() + static_cast<std::ptrdiff_t>(k));
        removed = true;
        break;
      }
    }
  }
  return ring;
}

}  // namespace

std::optional<std::vector<FootprintPolygon>> union_of_tiles(
    const std::vector<FootprintPolygon>& polygons, double tolerance) {
  // Directed edges, each ring turned so that the region lies on its left.
  Vertices vertices(tolerance);
  std::vector<std::pair<int, int>> edges;
  double area = 0.0;  // of the polygons, holes taken out
  const auto add_ring = [&](const std::vector<Vec2>& ring) {
    for (std::size_t k = 0; k < ring.size(); ++k) {
      const int a = vertices.id(ring[k]), b = vertices.id(ring[(k + 1) % ring.size()]);
      if (a != b) edges.emplace_back(a, b);
    }
  };
  for (const FootprintPolygon& polygon : polygons) {
    const std::vector<Vec2> outer = oriented(polygon.outer, true);
    if (outer.size() < 3) return std::nullopt;
    add_ring(outer);
    area += kernel::polygon_area(polygon.outer, polygon.holes);
    for (const auto& hole : polygon.holes) {
      const std::vector<Vec2> h = oriented(hole, false);
      if (h.size() < 3) return std::nullopt;
      add_ring(h);
    }
  }
  if (edges.empty() ||
      static_cast<double>(edges.size()) * static_cast<double>(vertices.size()) > kMaxTests) {
    return std::nullopt;
  }
  // A vertex lying on an edge (a neighbour's corner on a longer wall) splits it there.
  std::vector<std::pair<int, int>> split;
  for (const auto& [a, b] : edges) {
    const Vec2& pa = vertices.at(a);
    const Vec2& pb = vertices.at(b);
    const Vec2 d = pb - pa;
    const double length2 = d.squaredNorm();
    std::vector<std::pair<double, int>> on;  // (parameter along the edge, vertex)
    for (std::size_t v = 0; v < vertices.size(); ++v) {
      const int vi = static_cast<int>(v);
      if (vi == a || vi == b) continue;
      const Vec2& p = vertices.at(vi);
      if (p.x() < std::min(pa.x(), pb.x()) - tolerance ||
          p.x() > std::max(pa.x(), pb.x()) + tolerance ||
          p.y() < std::min(pa.y(), pb.y()) - tolerance ||
          p.y() > std::max(pa.y(), pb.y()) + tolerance) {
        continue;
      }
      const double t = (p - pa).dot(d) / length2;
      if (!(t > 0.0 && t < 1.0)) continue;
      if (kernel::segment_distance(p, pa, pb) <= tolerance) on.emplace_back(t, vi);
    }
    std::sort(on.begin(), on.end());
    int from = a;
    for (const auto& [t, v] : on) {
      split.emplace_back(from, v);
      from = v;
    }
    split.emplace_back(from, b);
  }
  // Shared walls cancel: an edge and its reverse. An edge twice one way is an overlap.
  std::map<std::pair<int, int>, int> count;
  for (const auto& e : split) {
    if (++count[e] > 1) return std::nullopt;
  }
  std::map<int, int> next;  // the boundary's one way on from each vertex
  for (const auto& [e, n] : count) {
    if (count.count({e.second, e.first}) != 0) continue;
    if (!next.emplace(e.first, e.second).second) return std::nullopt;  // two ways on: a pinch
  }
  // Rings, each from its smallest vertex id not yet walked.
  std::vector<std::vector<Vec2>> rings;
  while (!next.empty()) {
    const int start = next.begin()->first;
    std::vector<Vec2> ring;
    for (int v = start;;) {
      const auto it = next.find(v);
      if (it == next.end()) return std::nullopt;  // an open chain
      ring.push_back(vertices.at(v));
      v = it->second;
      next.erase(it);
      if (v == start) break;
    }
    ring = without_straight_corners(kernel::clean_ring(ring, 0.0), tolerance);
    if (ring.size() < 3 || kernel::ring_self_intersects(ring)) return std::nullopt;
    rings.push_back(std::move(ring));
  }
  for (std::size_t i = 0; i < rings.size(); ++i) {
    for (std::size_t j = i + 1; j < rings.size(); ++j) {
      if (kernel::rings_intersect(rings[i], rings[j])) return std::nullopt;
    }
  }
  // Rings that tile nest alternately: around a point of an outer ring the others wind
  // nought times (it stands free, or on an island in a courtyard), around a hole's once. A
  // ring inside an outer ring of the same turn (a room inside another) is an overlap.
  for (std::size_t r = 0; r < rings.size(); ++r) {
    int winding = 0;
    for (std::size_t q = 0; q < rings.size(); ++q) {
      if (q != r && kernel::inside_ring(rings[r].front(), rings[q])) {
        winding += kernel::ring_area(rings[q]) > 0.0 ? 1 : -1;
      }
    }
    if (winding != (kernel::ring_area(rings[r]) > 0.0 ? 0 : 1)) return std::nullopt;
  }
  // Holes go to the smallest outer ring around them.
  std::vector<FootprintPolygon> out;
  for (const auto& ring : rings) {
    const double a = kernel::ring_area(ring);
    if (a == 0.0) return std::nullopt;
    if (a > 0.0) out.push_back({ring, {}});
  }
  for (const auto& ring : rings) {
    if (kernel::ring_area(ring) > 0.0) continue;
    std::size_t best = out.size();
    for (std::size_t k = 0; k < out.size(); ++k) {
      if (!kernel::inside_ring(ring.front(), out[k].outer)) continue;
      if (best == out.size() ||
          kernel::ring_area(out[k].outer) < kernel::ring_area(out[best].outer)) {
        best = k;
      }
    }
    if (best == out.size()) return std::nullopt;
    out[best].holes.push_back(ring);
  }
  double kept = 0.0;
  for (const FootprintPolygon& p : out) kept += kernel::polygon_area(p.outer, p.holes);
  if (!(std::abs(kept - area) <= 1e-9 * area)) return std::nullopt;
  return out;
}

}  // namespace csgtile::assembly::detail
