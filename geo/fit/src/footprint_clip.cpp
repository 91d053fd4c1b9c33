// Footprint clipping for the roof partition (see footprint_clip.h), on Boost.Geometry's
// polygon intersection.

#include "footprint_clip.h"

#include <algorithm>
#include <cmath>
// Boost.Geometry's rescaling policy trips GCC 12's -Wmaybe-uninitialized once inlined here
// (a false positive inside Boost); this file alone instantiates it.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
// Without Boost.Geometry's rescaling to integers, which moves every output vertex by up to
// ~1e-7 of the extent: the parts' shared edges must keep their exact coordinates (input
// vertices are kept, crossings computed in double).
#define BOOST_GEOMETRY_NO_ROBUSTNESS
#include <boost/geometry.hpp>
#include <boost/geometry/geometries/point_xy.hpp>
#include <boost/geometry/geometries/polygon.hpp>

namespace csgtile::fit::detail {

namespace bg = boost::geometry;
using BPoint = bg::model::d2::point_xy<double>;
using BPolygon = bg::model::polygon<BPoint, false>;  // counter-clockwise outer rings, closed
using BMulti = bg::model::multi_polygon<BPolygon>;
using BBox = bg::model::box<BPoint>;

namespace {

BPolygon to_boost(const FramePolygon& p) {
  BPolygon out;
  for (const Vec2& q : p.outer) out.outer().emplace_back(q.x(), q.y());
  for (const auto& h : p.holes) {
    out.inners().emplace_back();
    for (const Vec2& q : h) out.inners().back().emplace_back(q.x(), q.y());
  }
  bg::correct(out);  // closes the rings and orients them as the type says
  return out;
}

std::vector<Vec2> from_ring(const bg::model::ring<BPoint, false>& ring) {
  std::vector<Vec2> out;
  for (const BPoint& q : ring) out.emplace_back(q.x(), q.y());
  if (out.size() > 1 && out.front() == out.back()) out.pop_back();
  return out;
}

}  // namespace

struct FootprintClip::Impl {
  BMulti shape;
  BBox box{};
};

FootprintClip::FootprintClip(const std::vector<geo::FootprintPolygon>& polygons, const Vec2& u,
                             const Vec2& v)
    : impl_(new Impl) {
  auto frame = [&](const std::vector<Vec2>& ring) {
    std::vector<Vec2> out;
    for (const Vec2& q : ring) out.emplace_back(q.dot(u), q.dot(v));
    return out;
  };
  // The polygons as one valid multipolygon: their union (a footprint's parts may touch).
  for (const geo::FootprintPolygon& p : polygons) {
    FramePolygon f{frame(p.outer), {}};
    for (const auto& h : p.holes) f.holes.push_back(frame(h));
    BMulti next;
    bg::union_(impl_->shape, to_boost(f), next);
    impl_->shape = std::move(next);
  }
  bg::envelope(impl_->shape, impl_->box);
}

FootprintClip::~FootprintClip() { delete impl_; }

bool FootprintClip::extent(double& a0, double& a1, double& b0, double& b1) const {
  if (!(bg::area(impl_->shape) > 0.0)) return false;
  a0 = impl_->box.min_corner().x();
  b0 = impl_->box.min_corner().y();
  a1 = impl_->box.max_corner().x();
  b1 = impl_->box.max_corner().y();
  return true;
}

double FootprintClip::area_in(double a0, double b0, double a1, double b1) const {
  const BBox cell(BPoint(a0, b0), BPoint(a1, b1));
  if (bg::disjoint(cell, impl_->box)) return 0.0;
  BPolygon rect;
  bg::convert(cell, rect);
  bg::correct(rect);
  BMulti in;
  bg::intersection(rect, impl_->shape, in);
  return bg::area(in);
}

std::vector<FramePolygon> FootprintClip::clip(const FramePolygon& polygon, double min_area) const {
  BMulti in;
  bg::intersection(to_boost(polygon), impl_->shape, in);
  std::vector<std::pair<double, FramePolygon>> pieces;
  for (const BPolygon& p : in) {
    const double area = bg::area(p);
    if (!(area >= min_area)) continue;
    FramePolygon f;
    f.outer = from_ring(p.outer());
    for (const auto& h : p.inners()) f.holes.push_back(from_ring(h));
    if (f.outer.size() >= 3) pieces.emplace_back(area, std::move(f));
  }
  std::stable_sort(pieces.begin(), pieces.end(),
                   [](const auto& x, const auto& y) { return x.first > y.first; });
  std::vector<FramePolygon> out;
  for (auto& [area, f] : pieces) out.push_back(std::move(f));
  return out;
}

FramePolygon oriented(const FramePolygon& polygon) {
  const BPolygon b = to_boost(polygon);
  FramePolygon out;
  out.outer = from_ring(b.outer());
  for (const auto& h : b.inners()) out.holes.push_back(from_ring(h));
  return out;
}

std::vector<Vec2> VertexSnap::ring(const std::vector<Vec2>& ring) {
  auto key = [&](const Vec2& q) {
    return std::pair<long long, long long>(static_cast<long long>(std::floor(q.x() / distance_)),
                                           static_cast<long long>(std::floor(q.y() / distance_)));
  };
  std::vector<Vec2> out;
  for (const Vec2& q : ring) {
    const auto [i, j] = key(q);
    std::optional<Vec2> rep;
    double best = distance_;
    for (long long dj = -1; dj <= 1; ++dj) {
      for (long long di = -1; di <= 1; ++di) {
        const auto it = seen_.find({i + di, j + dj});
        if (it == seen_.end()) continue;
        for (const Vec2& r : it->second) {
          const double d = (r - q).norm();
          if (d < best || (d == best && rep && (r.x() < rep->x()))) {
            best = d;
            rep = r;
          }
        }
      }
    }
    if (!rep) {
      seen_[{i, j}].push_back(q);
      rep = q;
    }
    if (out.empty() || out.back() != *rep) out.push_back(*rep);
  }
  while (out.size() > 1 && out.front() == out.back()) out.pop_back();
  // Spikes: a vertex whose neighbours are one point.
  for (bool changed = true; changed && out.size() >= 3;) {
    changed = false;
    for (std::size_t k = 0; k < out.size() && out.size() >= 3; ++k) {
      const Vec2& prev = out[(k + out.size() - 1) % out.size()];
      const Vec2& next = out[(k + 1) % out.size()];
      if (prev == next) {
        // Drop the vertex and one copy of its neighbour.
        const std::size_t n = (k + 1) % out.size();
        out.erase(out.begin() + static_cast<std::ptrdiff_t>(std::max(k, n)));
        out.erase(out.begin() + static_cast<std::ptrdiff_t>(std::min(k, n)));
        changed = true;
        break;
      }
    }
  }
  return out;
}

std::optional<FramePolygon> VertexSnap::snap(const FramePolygon& polygon) {
  FramePolygon out;
  out.outer = ring(polygon.outer);
  if (out.outer.size() < 3 || !(std::abs(polygon_area(out.outer, {})) > 0.0)) return std::nullopt;
  for (const auto& h : polygon.holes) {
    auto hole = ring(h);
    if (hole.size() >= 3 && std::abs(polygon_area(hole, {})) > 0.0) out.holes.push_back(hole);
  }
  return out;
}

void share_vertices(std::vector<std::vector<FramePolygon>>& polygons, double distance) {
  if (!(distance > 0.0)) return;
  // Every vertex once, hashed on cells of a metre (or the distance, when larger).
  const double size = std::max(1.0, distance);
  auto key = [&](double x, double y) {
    return std::pair<long long, long long>(static_cast<long long>(std::floor(x / size)),
                                           static_cast<long long>(std::floor(y / size)));
  };
  std::map<std::pair<long long, long long>, std::vector<Vec2>> cells;
  auto add = [&](const std::vector<Vec2>& ring) {
    for (const Vec2& q : ring) {
      auto& list = cells[key(q.x(), q.y())];
      if (std::find(list.begin(), list.end(), q) == list.end()) list.push_back(q);
    }
  };
  for (const auto& pieces : polygons) {
    for (const FramePolygon& p : pieces) {
      add(p.outer);
      for (const auto& h : p.holes) add(h);
    }
  }
  auto share = [&](std::vector<Vec2>& ring) {
    std::vector<Vec2> out;
    const std::size_t n = ring.size();
    for (std::size_t i = 0; i < n; ++i) {
      const Vec2 a = ring[i], b = ring[(i + 1) % n];
      out.push_back(a);
      const Vec2 d = b - a;
      const double len2 = d.squaredNorm();
      if (!(len2 > 0.0)) continue;
      std::vector<std::pair<double, Vec2>> on;  // (position along the edge, vertex)
      const auto lo = key(std::min(a.x(), b.x()) - distance, std::min(a.y(), b.y()) - distance);
      const auto hi = key(std::max(a.x(), b.x()) + distance, std::max(a.y(), b.y()) + distance);
      for (long long cx = lo.first; cx <= hi.first; ++cx) {
        for (long long cy = lo.second; cy <= hi.second; ++cy) {
          const auto it = cells.find({cx, cy});
          if (it == cells.end()) continue;
          for (const Vec2& q : it->second) {
            const double t = (q - a).dot(d) / len2;
            if (!(t > 0.0 && t < 1.0) || q == a || q == b) continue;
            if ((a + t * d - q).norm() > distance) continue;
            if (std::find(ring.begin(), ring.end(), q) != ring.end()) continue;
            on.emplace_back(t, q);
          }
        }
      }
      std::sort(on.begin(), on.end(), [](const auto& x, const auto& y) {
        if (x.first != y.first) return x.first < y.first;
        return x.second.x() != y.second.x() ? x.second.x() < y.second.x()
                                            : x.second.y() < y.second.y();
      });
      for (const auto& [t, q] : on) {
        if (out.back() != q) out.push_back(q);
      }
    }
    ring = std::move(out);
  };
  for (auto& pieces : polygons) {
    for (FramePolygon& p : pieces) {
      share(p.outer);
      for (auto& h : p.holes) share(h);
    }
  }
}

std::optional<PrincipalFrame> footprint_frame(const std::vector<geo::FootprintPolygon>& polygons) {
  // Each edge's direction modulo 90°, weighted by its length; the direction whose ±1.5°
  // holds the most length wins (ties: the first edge), refined to those edges' weighted
  // mean (as a doubled angle on the circle of period 90°).
  struct Edge {
    double angle, length;  // angle in [0, 90) degrees
  };
  std::vector<Edge> edges;
  std::vector<Vec2> corners;
  for (const auto& p : polygons) {
    corners.insert(corners.end(), p.outer.begin(), p.outer.end());
    for (std::size_t i = 0; i < p.outer.size(); ++i) {
      const Vec2 d = p.outer[(i + 1) % p.outer.size()] - p.outer[i];
      const double len = d.norm();
      if (!(len > 0.0)) continue;
      double a = std::atan2(d.y(), d.x()) * 180.0 / M_PI;
      a = std::fmod(std::fmod(a, 90.0) + 90.0, 90.0);
      edges.push_back({a, len});
    }
  }
  if (edges.empty() || corners.size() < 3) return std::nullopt;
  auto gap = [](double a, double b) {
    const double d = std::abs(a - b);
    return std::min(d, 90.0 - d);
  };
  std::size_t best = 0;
  double best_weight = -1.0;
  for (std::size_t i = 0; i < edges.size(); ++i) {
    double w = 0.0;
    for (const Edge& e : edges) w += gap(e.angle, edges[i].angle) <= 1.5 ? e.length : 0.0;
    if (w > best_weight + 1e-9) {
      best_weight = w;
      best = i;
    }
  }
  double sx = 0.0, sy = 0.0;
  for (const Edge& e : edges) {
    if (gap(e.angle, edges[best].angle) > 1.5) continue;
    const double t = e.angle * M_PI / 45.0;  // period 90° → full circle
    sx += e.length * std::cos(t);
    sy += e.length * std::sin(t);
  }
  const double angle = std::atan2(sy, sx) / 4.0;  // back to radians of period 90°
  PrincipalFrame f;
  f.u = Vec2(std::cos(angle), std::sin(angle));
  f.v = Vec2(-f.u.y(), f.u.x());
  f.a0 = f.b0 = INFINITY;
  f.a1 = f.b1 = -INFINITY;
  for (const Vec2& q : corners) {
    f.a0 = std::min(f.a0, q.dot(f.u)), f.a1 = std::max(f.a1, q.dot(f.u));
    f.b0 = std::min(f.b0, q.dot(f.v)), f.b1 = std::max(f.b1, q.dot(f.v));
  }
  return f;
}

}  // namespace csgtile::fit::detail
