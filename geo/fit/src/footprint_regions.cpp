// Which footprint each point of a tile belongs to (see fit_internal.h): a grid over the
// footprints' boxes, then point in polygon, else the nearest boundary within the buffer; the
// footprints' rings straightened.

#include <algorithm>
#include <cmath>
#include <map>

#include "fit_internal.h"
#include "plane2d.h"

namespace csgtile::fit::detail {

std::vector<Vec2> straightened_ring(const std::vector<Vec2>& ring, double deviation) {
  std::vector<Vec2> out = ring;
  // Repeatedly the vertex nearest to the chord of its neighbours, while within `deviation`
  // (ties: the first), so that the result does not depend on where the ring starts more
  // than ties do.
  while (out.size() > 3) {
    std::size_t best = out.size();
    double least = deviation;
    for (std::size_t k = 0; k < out.size(); ++k) {
      const Vec2& a = out[(k + out.size() - 1) % out.size()];
      const Vec2& b = out[(k + 1) % out.size()];
      const Vec2 d = b - a;
      const double len = d.norm();
      const Vec2 w = out[k] - a;
      const double dist = len > 0.0 ? std::abs(d.x() * w.y() - d.y() * w.x()) / len : w.norm();
      // Only where the ring goes on (not a spike back along itself).
      if (dist <= least && (len == 0.0 || w.dot(d) > 0.0) &&
          (len == 0.0 || (out[k] - b).dot(d) < 0.0)) {
        least = dist;
        best = k;
        if (dist == 0.0) break;
      }
    }
    if (best == out.size()) break;
    out.erase(out.begin() + static_cast<std::ptrdiff_t>(best));
  }
  return out;
}

std::vector<int> footprint_of_points(std::span<const Vec3> points,
                                     std::span<const geo::Footprint> footprints, double buffer) {
  std::vector<int> out(points.size(), -1);
  if (footprints.empty()) return out;
  const double cell = 16.0;
  auto key = [&](double x, double y) {
    return std::pair<long long, long long>(static_cast<long long>(std::floor(x / cell)),
                                           static_cast<long long>(std::floor(y / cell)));
  };
  std::map<std::pair<long long, long long>, std::vector<int>> grid;
  for (std::size_t f = 0; f < footprints.size(); ++f) {
    double x0 = INFINITY, y0 = INFINITY, x1 = -INFINITY, y1 = -INFINITY;
    for (const auto& p : footprints[f].polygons) {
      for (const Vec2& q : p.outer) {
        x0 = std::min(x0, q.x()), y0 = std::min(y0, q.y());
        x1 = std::max(x1, q.x()), y1 = std::max(y1, q.y());
      }
    }
    if (!(x0 <= x1) || !(y0 <= y1)) continue;
    // A footprint of a whole country's extent is a wrong CRS, not a building: capped.
    if ((x1 - x0) / cell > 1e4 || (y1 - y0) / cell > 1e4) continue;
    const auto [i0, j0] = key(x0 - buffer, y0 - buffer);
    const auto [i1, j1] = key(x1 + buffer, y1 + buffer);
    for (long long j = j0; j <= j1; ++j) {
      for (long long i = i0; i <= i1; ++i) grid[{i, j}].push_back(static_cast<int>(f));
    }
  }
  auto inside = [&](const Vec2& q, const geo::Footprint& fp) {
    for (const auto& p : fp.polygons) {
      if (!inside_ring(q, p.outer)) continue;
      bool in_hole = false;
      for (const auto& h : p.holes) in_hole = in_hole || inside_ring(q, h);
      if (!in_hole) return true;
    }
    return false;
  };
  auto distance = [&](const Vec2& q, const geo::Footprint& fp) {
    double best = INFINITY;
    auto ring = [&](const std::vector<Vec2>& r) {
      for (std::size_t k = 0; k < r.size(); ++k) {
        const Vec2& a = r[k];
        const Vec2& b = r[(k + 1) % r.size()];
        const Vec2 d = b - a;
        const double len2 = d.squaredNorm();
        const double t = len2 > 0.0 ? std::clamp((q - a).dot(d) / len2, 0.0, 1.0) : 0.0;
        best = std::min(best, (a + t * d - q).norm());
      }
    };
    for (const auto& p : fp.polygons) {
      ring(p.outer);
      for (const auto& h : p.holes) ring(h);
    }
    return best;
  };
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!points[i].allFinite()) continue;
    const Vec2 q(points[i].x(), points[i].y());
    const auto it = grid.find(key(q.x(), q.y()));
    if (it == grid.end()) continue;
    double nearest = buffer;
    for (int f : it->second) {  // ascending: the first footprint holding it wins
      const geo::Footprint& fp = footprints[static_cast<std::size_t>(f)];
      if (inside(q, fp)) {
        out[i] = f;
        break;
      }
      const double d = distance(q, fp);
      if (d <= nearest) {
        if (d < nearest || out[i] < 0) out[i] = f;
        nearest = d;
      }
    }
  }
  return out;
}

}  // namespace csgtile::fit::detail
