// Point-to-mesh distances on an xy bucket grid (csgtile/kernel/mesh_distance.h).

#include "csgtile/kernel/mesh_distance.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace csgtile::kernel {

// The closest point found by the region of the triangle's plane it falls in (a vertex, an edge
// or the face), after Ericson, Real-Time Collision Detection, §5.1.5.
double triangle_distance2(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0.0 && d2 <= 0.0) return ap.squaredNorm();
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0.0 && d4 <= d3) return bp.squaredNorm();
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) return (ap - d1 / (d1 - d3) * ab).squaredNorm();
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0.0 && d5 <= d6) return cp.squaredNorm();
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) return (ap - d2 / (d2 - d6) * ac).squaredNorm();
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0) {
    return (bp - (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b)).squaredNorm();
  }
  const double sum = va + vb + vc;
  if (!(std::abs(sum) > 0.0)) {  // a degenerate triangle: its longest side is all there is
    double best = std::numeric_limits<double>::infinity();
    for (const auto& [s, e] : {std::pair{a, b}, std::pair{b, c}, std::pair{c, a}}) {
      const Vec3 d = e - s;
      const double len2 = d.squaredNorm();
      const double t = len2 > 0.0 ? std::clamp((p - s).dot(d) / len2, 0.0, 1.0) : 0.0;
      best = std::min(best, (p - s - t * d).squaredNorm());
    }
    return best;
  }
  const double scale = 1.0 / sum;
  return (ap - vb * scale * ab - vc * scale * ac).squaredNorm();
}

MeshDistance::MeshDistance(const Mesh& mesh) {
  triangles_.reserve(mesh.triangles.size());
  for (const auto& k : mesh.triangles) {
    Triangle t{mesh.vertices[k[0]], mesh.vertices[k[1]], mesh.vertices[k[2]], {}, {}};
    if (!t.a.allFinite() || !t.b.allFinite() || !t.c.allFinite()) continue;
    t.low = t.a.cwiseMin(t.b).cwiseMin(t.c);
    t.high = t.a.cwiseMax(t.b).cwiseMax(t.c);
    bounds_.add(t.low);
    bounds_.add(t.high);
    triangles_.push_back(t);
  }
  if (triangles_.empty()) return;
  // About one triangle per cell along each side's square root: the grid has at most about as
  // many cells as triangles.
  const double w = bounds_.max.x() - bounds_.min.x(), h = bounds_.max.y() - bounds_.min.y();
  const double side = std::ceil(std::sqrt(static_cast<double>(triangles_.size())));
  cell_ = std::max(w, h) / side;
  if (!(cell_ > 1e-9)) cell_ = 1.0;
  x0_ = bounds_.min.x();
  y0_ = bounds_.min.y();
  nx_ = static_cast<long long>(w / cell_) + 1;
  ny_ = static_cast<long long>(h / cell_) + 1;
  const auto cell_range = [&](const Triangle& t) {
    const auto clamp_x = [&](double x) {
      return std::clamp(static_cast<long long>(std::floor((x - x0_) / cell_)), 0LL, nx_ - 1);
    };
    const auto clamp_y = [&](double y) {
      return std::clamp(static_cast<long long>(std::floor((y - y0_) / cell_)), 0LL, ny_ - 1);
    };
    return std::array<long long, 4>{clamp_x(t.low.x()), clamp_x(t.high.x()), clamp_y(t.low.y()),
                                    clamp_y(t.high.y())};
  };
  // Counting sort of (cell, triangle): triangles keep their mesh order within a cell.
  start_.assign(static_cast<std::size_t>(nx_ * ny_) + 1, 0);
  for (const Triangle& t : triangles_) {
    const auto r = cell_range(t);
    for (long long j = r[2]; j <= r[3]; ++j)
      for (long long i = r[0]; i <= r[1]; ++i) ++start_[static_cast<std::size_t>(j * nx_ + i) + 1];
  }
  for (std::size_t c = 1; c < start_.size(); ++c) start_[c] += start_[c - 1];
  items_.resize(start_.back());
  std::vector<std::uint32_t> fill(start_.begin(), start_.end() - 1);
  for (std::uint32_t k = 0; k < triangles_.size(); ++k) {
    const auto r = cell_range(triangles_[k]);
    for (long long j = r[2]; j <= r[3]; ++j)
      for (long long i = r[0]; i <= r[1]; ++i)
        items_[fill[static_cast<std::size_t>(j * nx_ + i)]++] = k;
  }
}

double MeshDistance::distance(const Vec3& p) const { return std::sqrt(distance2(p)); }

double MeshDistance::distance2(const Vec3& p) const {
  double best = std::numeric_limits<double>::infinity();
  if (triangles_.empty() || !p.allFinite()) return best;
  const auto ci =
      std::clamp(static_cast<long long>(std::floor((p.x() - x0_) / cell_)), 0LL, nx_ - 1);
  const auto cj =
      std::clamp(static_cast<long long>(std::floor((p.y() - y0_) / cell_)), 0LL, ny_ - 1);
  const auto visit = [&](long long i, long long j) {
    const std::size_t c = static_cast<std::size_t>(j * nx_ + i);
    for (std::uint32_t k = start_[c]; k < start_[c + 1]; ++k) {
      const Triangle& t = triangles_[items_[k]];
      // A triangle whose box is farther than the best so far cannot be closer.
      const Vec3 gap = (t.low - p).cwiseMax(p - t.high).cwiseMax(Vec3::Zero());
      if (gap.squaredNorm() >= best) continue;
      best = std::min(best, triangle_distance2(p, t.a, t.b, t.c));
    }
  };
  // Rings of cells around the point's (clamped) cell, until every cell not yet visited lies
  // farther in xy than the best distance so far.
  for (long long r = 0;; ++r) {
    const long long i0 = ci - r, i1 = ci + r, j0 = cj - r, j1 = cj + r;
    for (long long j = std::max(j0, 0LL); j <= std::min(j1, ny_ - 1); ++j) {
      const bool edge_row = j == j0 || j == j1;
      for (long long i = std::max(i0, 0LL); i <= std::min(i1, nx_ - 1); ++i) {
        if (edge_row || i == i0 || i == i1) visit(i, j);
      }
    }
    double beyond = std::numeric_limits<double>::infinity();  // xy distance to unvisited cells
    if (i0 > 0) beyond = std::min(beyond, p.x() - (x0_ + static_cast<double>(i0) * cell_));
    if (i1 < nx_ - 1) beyond = std::min(beyond, x0_ + static_cast<double>(i1 + 1) * cell_ - p.x());
    if (j0 > 0) beyond = std::min(beyond, p.y() - (y0_ + static_cast<double>(j0) * cell_));
    if (j1 < ny_ - 1) beyond = std::min(beyond, y0_ + static_cast<double>(j1 + 1) * cell_ - p.y());
    if (std::isinf(beyond) || beyond * beyond >= best) break;
  }
  return best;
}

bool MeshDistance::covers(double x, double y) const {
  if (triangles_.empty() || !std::isfinite(x) || !std::isfinite(y)) return false;
  const double fi = std::floor((x - x0_) / cell_), fj = std::floor((y - y0_) / cell_);
  if (fi < 0.0 || fj < 0.0 || fi >= static_cast<double>(nx_) || fj >= static_cast<double>(ny_)) {
    // The last row and column of the grid end past the box; a point just past the box's
    // maximum is not over it.
    return false;
  }
  const std::size_t c =
      static_cast<std::size_t>(static_cast<long long>(fj) * nx_ + static_cast<long long>(fi));
  const auto cross = [](double ax, double ay, double bx, double by) { return ax * by - ay * bx; };
  for (std::uint32_t k = start_[c]; k < start_[c + 1]; ++k) {
    const Triangle& t = triangles_[items_[k]];
    if (x < t.low.x() || x > t.high.x() || y < t.low.y() || y > t.high.y()) continue;
    const double area =
        cross(t.b.x() - t.a.x(), t.b.y() - t.a.y(), t.c.x() - t.a.x(), t.c.y() - t.a.y());
    const double extent = (t.high - t.low).head<2>().squaredNorm();
    if (!(std::abs(area) > 1e-12 * extent)) continue;  // vertical: a wall covers no area
    const double s = area > 0.0 ? 1.0 : -1.0;
    const double slack = -1e-12 * std::abs(area);
    if (s * cross(t.b.x() - t.a.x(), t.b.y() - t.a.y(), x - t.a.x(), y - t.a.y()) >= slack &&
        s * cross(t.c.x() - t.b.x(), t.c.y() - t.b.y(), x - t.b.x(), y - t.b.y()) >= slack &&
        s * cross(t.a.x() - t.c.x(), t.a.y() - t.c.y(), x - t.c.x(), y - t.c.y()) >= slack) {
      return true;
    }
  }
  return false;
}

}  // namespace csgtile::kernel
