// Rings and polygons in the plane (polygon2d.h).

#include "csgtile/kernel/polygon2d.h"

#include "predicates/predicates.h"

#include <algorithm>
#include <cmath>

namespace csgtile::kernel {

namespace {
// z of the cross product a × b.
double cross2(const Vec2& a, const Vec2& b) { return a.x() * b.y() - a.y() * b.x(); }
double cross(const Vec2& o, const Vec2& a, const Vec2& b) {
  return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
}
int sign(double v) { return (v > 0) - (v < 0); }
bool on_segment(const Vec2& p, const Vec2& a, const Vec2& b) {
  return std::min(a.x(), b.x()) <= p.x() && p.x() <= std::max(a.x(), b.x()) &&
         std::min(a.y(), b.y()) <= p.y() && p.y() <= std::max(a.y(), b.y());
}
// Closed segments [a,b] and [c,d] share a point. Orientation signs of exact double
// products: profiles come from user input in metres, so products are far from overflow.
bool segments_touch(const Vec2& a, const Vec2& b, const Vec2& c, const Vec2& d) {
  const int d1 = sign(cross(c, d, a)), d2 = sign(cross(c, d, b));
  const int d3 = sign(cross(a, b, c)), d4 = sign(cross(a, b, d));
  if (d1 * d2 < 0 && d3 * d4 < 0) return true;
  if (d1 == 0 && on_segment(a, c, d)) return true;
  if (d2 == 0 && on_segment(b, c, d)) return true;
  if (d3 == 0 && on_segment(c, a, b)) return true;
  if (d4 == 0 && on_segment(d, a, b)) return true;
  return false;
}
}  // namespace

double ring_area(const std::vector<Vec2>& ring) {
  double a = 0.0;
  for (std::size_t i = 0; i < ring.size(); ++i) a += cross2(ring[i], ring[(i + 1) % ring.size()]);
  return 0.5 * a;
}

bool inside_ring(const Vec2& p, const std::vector<Vec2>& ring) {
  bool in = false;
  for (std::size_t i = 0, j = ring.size() - 1; i < ring.size(); j = i++) {
    const Vec2& a = ring[i];
    const Vec2& b = ring[j];
    if ((a.y() > p.y()) != (b.y() > p.y()) &&
        p.x() < (b.x() - a.x()) * (p.y() - a.y()) / (b.y() - a.y()) + a.x()) {
      in = !in;
    }
  }
  return in;
}

bool inside_polygon(const Vec2& p, const std::vector<Vec2>& outer,
                    const std::vector<std::vector<Vec2>>& holes) {
  bool in = inside_ring(p, outer);
  for (const auto& hole : holes) in = in && !inside_ring(p, hole);
  return in;
}

double segment_distance(const Vec2& p, const Vec2& a, const Vec2& b) {
  const Vec2 ab = b - a;
  const double len2 = ab.squaredNorm();
  const double t = len2 > 0.0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
  return (p - (a + t * ab)).norm();
}

double boundary_distance(const Vec2& p, const std::vector<Vec2>& outer,
                         const std::vector<std::vector<Vec2>>& holes) {
  double side = INFINITY;
  auto edges = [&](const std::vector<Vec2>& ring) {
    for (std::size_t i = 0; i < ring.size(); ++i) {
      side = std::min(side, segment_distance(p, ring[i], ring[(i + 1) % ring.size()]));
    }
  };
  edges(outer);
  for (const auto& hole : holes) edges(hole);
  return side;
}

double polygon_perimeter(const std::vector<Vec2>& outer,
                         const std::vector<std::vector<Vec2>>& holes) {
  double perimeter = 0.0;
  auto edges = [&](const std::vector<Vec2>& ring) {
    for (std::size_t k = 0; k < ring.size(); ++k) {
      perimeter += (ring[(k + 1) % ring.size()] - ring[k]).norm();
    }
  };
  edges(outer);
  for (const auto& hole : holes) edges(hole);
  return perimeter;
}

double polygon_area(const std::vector<Vec2>& outer, const std::vector<std::vector<Vec2>>& holes) {
  double area = std::abs(ring_area(outer));
  for (const auto& hole : holes) area -= std::abs(ring_area(hole));
  return area;
}

void douglas_peucker(const std::vector<Vec2>& points, std::size_t i, std::size_t j, double tol,
                     std::vector<char>& keep) {
  const std::size_t n = points.size();
  if ((j + n - i) % n < 2) return;
  double worst = -1.0;
  std::size_t at = i;
  for (std::size_t k = (i + 1) % n; k != j; k = (k + 1) % n) {
    const double d = segment_distance(points[k], points[i], points[j]);
    if (d > worst) {
      worst = d;
      at = k;
    }
  }
  if (worst <= tol) return;
  keep[at] = 1;
  douglas_peucker(points, i, at, tol, keep);
  douglas_peucker(points, at, j, tol, keep);
}

std::vector<Vec2> clean_ring(const std::vector<Vec2>& ring, double eps) {
  std::vector<Vec2> out;
  for (const Vec2& p : ring) {
    if (out.empty() || (p - out.back()).norm() > eps) out.push_back(p);
  }
  while (out.size() > 1 && (out.front() - out.back()).norm() <= eps) out.pop_back();
  // Drop middle points of straight runs (repeat until stable: removing one can expose another).
  bool changed = true;
  while (changed && out.size() >= 3) {
    changed = false;
    for (std::size_t i = 0; i < out.size() && out.size() >= 3; ++i) {
      const Vec2& a = out[(i + out.size() - 1) % out.size()];
      const Vec2& b = out[i];
      const Vec2& c = out[(i + 1) % out.size()];
      const double scale = (c - a).norm() * std::max((b - a).norm(), (c - b).norm());
      if (std::abs(cross(a, b, c)) <= 1e-14 * scale && (b - a).dot(c - b) > 0) {
        out.erase(out.begin() + static_cast<std::ptrdiff_t>(i));
        changed = true;
        break;
      }
    }
  }
  return out;
}

bool ring_self_intersects(const std::vector<Vec2>& ring) {
  const std::size_t n = ring.size();
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = i + 1; j < n; ++j) {
      const bool adjacent = j == i + 1 || (i == 0 && j == n - 1);
      const Vec2 &a = ring[i], &b = ring[(i + 1) % n], &c = ring[j], &d = ring[(j + 1) % n];
      if (adjacent) {
        // Adjacent edges share one vertex; they must not fold back onto each other.
        const Vec2& shared = (j == i + 1) ? b : a;
        const Vec2& p = (j == i + 1) ? a : b;
        const Vec2& q = (j == i + 1) ? d : c;
        if (cross(shared, p, q) == 0.0 && (p - shared).dot(q - shared) > 0) return true;
        continue;
      }
      if (segments_touch(a, b, c, d)) return true;
    }
  }
  return false;
}

bool rings_intersect(const std::vector<Vec2>& a, const std::vector<Vec2>& b) {
  for (std::size_t i = 0; i < a.size(); ++i) {
    for (std::size_t j = 0; j < b.size(); ++j) {
      if (segments_touch(a[i], a[(i + 1) % a.size()], b[j], b[(j + 1) % b.size()])) return true;
    }
  }
  return false;
}

// ---- Exact rings on an integer grid ----------------------------------------------------------
// Grid vertices are exact as doubles, so the kernel's exact predicates decide for them.

namespace {

Vec2 grid_point(const GridVertex& p) {
  return {static_cast<double>(p[0]), static_cast<double>(p[1])};
}

}  // namespace

int grid_orientation(const GridVertex& a, const GridVertex& b, const GridVertex& c) {
  return predicates::orient2d(grid_point(a), grid_point(b), grid_point(c));
}

bool grid_segments_conflict(const GridVertex& a, const GridVertex& b, const GridVertex& c,
                            const GridVertex& d) {
  switch (
      predicates::classify_segments(grid_point(a), grid_point(b), grid_point(c), grid_point(d))) {
    case predicates::SegmentRelation::Disjoint:
      return false;
    case predicates::SegmentRelation::Touch:
      // One common point: allowed when it is an end of both.
      return !(a == c || a == d || b == c || b == d);
    case predicates::SegmentRelation::Cross:
    case predicates::SegmentRelation::Overlap:
      return true;
  }
  return true;
}

long long grid_ring_area2(const std::vector<GridVertex>& ring) {
  long long a = 0;
  for (std::size_t k = 0; k < ring.size(); ++k) {
    const GridVertex& p = ring[k];
    const GridVertex& q = ring[(k + 1) % ring.size()];
    a += p[0] * q[1] - q[0] * p[1];
  }
  return a;
}

bool grid_midpoint_inside(const GridVertex& a, const GridVertex& b,
                          const std::vector<GridVertex>& ring) {
  // The half-integer midpoint is exact too; the crossing rule is the even-odd test's.
  const Vec2 q = 0.5 * (grid_point(a) + grid_point(b));
  bool in = false;
  for (std::size_t k = 0, l = ring.size() - 1; k < ring.size(); l = k++) {
    if (predicates::crosses_ray(grid_point(ring[l]), grid_point(ring[k]), q)) in = !in;
  }
  return in;
}

}  // namespace csgtile::kernel
