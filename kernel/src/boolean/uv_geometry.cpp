#include "boolean/uv_geometry.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace csgtile::kernel::detail {

std::vector<Vec2> sample_use(const BModel& m, const BUse& use, int samples) {
  const BEdge& e = m.edges[static_cast<std::size_t>(use.edge)];
  const int n = use.pcurve->kind() == Curve2dKind::Line ? 1 : samples;
  std::vector<Vec2> out;
  out.reserve(static_cast<std::size_t>(n) + 1);
  for (int i = 0; i <= n; ++i) {
    const double f = static_cast<double>(i) / n;
    const double t = use.forward ? e.t0 + (e.t1 - e.t0) * f : e.t1 - (e.t1 - e.t0) * f;
    out.push_back(use.pcurve->point(t));
  }
  return out;
}

FacePolygon face_polygon(const BModel& m, const BFace& face) {
  FacePolygon p;
  p.u_period = face.surface->u_period();
  p.v_period = face.surface->v_period();
  p.min = Vec2::Constant(std::numeric_limits<double>::infinity());
  p.max = -p.min;
  for (const BLoop& loop : face.loops) {
    std::vector<Vec2> pts;
    for (const BUse& use : loop) {
      std::vector<Vec2> s = sample_use(m, use, 48);
      pts.insert(pts.end(), s.begin(), s.end() - 1);
    }
    for (const Vec2& q : pts) {
      p.min = p.min.cwiseMin(q);
      p.max = p.max.cwiseMax(q);
    }
    p.loops.push_back(std::move(pts));
  }
  return p;
}

namespace {
double segment_distance(const Vec2& p, const Vec2& a, const Vec2& b) {
  const Vec2 d = b - a;
  const double l2 = d.squaredNorm();
  const double t = l2 > 0 ? std::clamp((p - a).dot(d) / l2, 0.0, 1.0) : 0.0;
  return (p - (a + t * d)).norm();
}
}  // namespace

double FacePolygon::boundary_distance(const Vec2& uv) const {
  double best = std::numeric_limits<double>::infinity();
  for (const auto& loop : loops) {
    for (std::size_t i = 0; i < loop.size(); ++i) {
      best = std::min(best, segment_distance(uv, loop[i], loop[(i + 1) % loop.size()]));
    }
  }
  return best;
}

std::optional<bool> FacePolygon::inside(const Vec2& uv, double margin) const {
  if (boundary_distance(uv) <= margin) return std::nullopt;
  bool in = false;
  for (const auto& loop : loops) {
    for (std::size_t i = 0, n = loop.size(), j = n - 1; i < n; j = i++) {
      const Vec2& a = loop[i];
      const Vec2& b = loop[j];
      if ((a.y() > uv.y()) != (b.y() > uv.y()) &&
          uv.x() < (b.x() - a.x()) * (uv.y() - a.y()) / (b.y() - a.y()) + a.x()) {
        in = !in;
      }
    }
  }
  return in;
}

std::optional<Vec2> FacePolygon::shift_inside(const Vec2& uv, double margin) const {
  const int ku = u_period > 0 ? 2 : 0, kv = v_period > 0 ? 2 : 0;
  for (int i = -ku; i <= ku; ++i) {
    for (int j = -kv; j <= kv; ++j) {
      const Vec2 offset(i * u_period, j * v_period);
      const Vec2 q = uv + offset;
      if (q.x() < min.x() - margin || q.x() > max.x() + margin || q.y() < min.y() - margin ||
          q.y() > max.y() + margin) {
        continue;
      }
      auto in = inside(q, margin);
      if (in && *in) return offset;
    }
  }
  return std::nullopt;
}

std::vector<Crossing> intersect_pcurves(const Curve2d& a, double t0, double t1, const Curve2d& b,
                                        double s0, double s1, double tolerance) {
  auto samples_of = [](const Curve2d& c) { return c.kind() == Curve2dKind::Line ? 1 : 96; };
  const int na = samples_of(a), nb = samples_of(b);
  std::vector<Vec2> pa, pb;
  for (int i = 0; i <= na; ++i) pa.push_back(a.point(t0 + (t1 - t0) * i / na));
  for (int i = 0; i <= nb; ++i) pb.push_back(b.point(s0 + (s1 - s0) * i / nb));
  std::vector<Crossing> found;
  // Candidate pairs: segments whose boxes meet (grown by a margin for curvature).
  for (int i = 0; i < na; ++i) {
    const Vec2 amin = pa[i].cwiseMin(pa[i + 1]), amax = pa[i].cwiseMax(pa[i + 1]);
    const double grow_a = 0.05 * (pa[i + 1] - pa[i]).norm() + tolerance;
    for (int j = 0; j < nb; ++j) {
      const Vec2 bmin = pb[j].cwiseMin(pb[j + 1]), bmax = pb[j].cwiseMax(pb[j + 1]);
      const double grow = grow_a + 0.05 * (pb[j + 1] - pb[j]).norm();
      if ((amin.array() - grow > bmax.array()).any() || (bmin.array() - grow > amax.array()).any()) {
        continue;
      }
      // Start from the segments' own intersection (or their midpoints) and refine.
      const Vec2 da = pa[i + 1] - pa[i], db = pb[j + 1] - pb[j];
      const double den = da.x() * db.y() - da.y() * db.x();
      double fa = 0.5, fb = 0.5;
      if (std::abs(den) > 1e-300) {
        const Vec2 w = pb[j] - pa[i];
        fa = std::clamp((w.x() * db.y() - w.y() * db.x()) / den, 0.0, 1.0);
        fb = std::clamp((w.x() * da.y() - w.y() * da.x()) / den, 0.0, 1.0);
      }
      double t = t0 + (t1 - t0) * (i + fa) / na;
      double s = s0 + (s1 - s0) * (j + fb) / nb;
      bool converged = false;
      for (int it = 0; it < 40; ++it) {
        const Vec2 f = a.point(t) - b.point(s);
        if (f.norm() <= tolerance * 1e-3) {
          converged = true;
          break;
        }
        const Vec2 ja = a.derivative(t), jb = -b.derivative(s);
        const double det = ja.x() * jb.y() - ja.y() * jb.x();
        if (std::abs(det) < 1e-300) break;
        const double dt = (f.x() * jb.y() - f.y() * jb.x()) / det;
        const double ds = (ja.x() * f.y() - ja.y() * f.x()) / det;
        t -= dt;
        s -= ds;
        if (std::abs(dt) + std::abs(ds) < 1e-15 * (1 + std::abs(t) + std::abs(s))) {
          converged = (a.point(t) - b.point(s)).norm() <= tolerance;
          break;
        }
      }
      if (!converged) {
        // Tangential contact converges slowly: accept a close approach.
        if ((a.point(t) - b.point(s)).norm() > tolerance) continue;
      }
      const double pt = 1e-9 * std::max(1.0, std::abs(t1 - t0)), ps = 1e-9 * std::max(1.0, std::abs(s1 - s0));
      if (t < t0 - pt || t > t1 + pt || s < s0 - ps || s > s1 + ps) continue;
      t = std::clamp(t, t0, t1);
      s = std::clamp(s, s0, s1);
      // Curves that run along each other (overlapping boundaries of coincident faces) do
      // not cross: their shared stretch is handled by vertex splits, not crossings.
      {
        const Vec2 ta = a.derivative(t), tb = b.derivative(s);
        const double cross = std::abs(ta.x() * tb.y() - ta.y() * tb.x());
        if (cross <= 1e-7 * ta.norm() * tb.norm()) {
          const double step = 1e-3 * (t1 - t0);
          auto near_b = [&](const Vec2& q) {
            double best = std::numeric_limits<double>::infinity();
            for (int k = 0; k < nb; ++k) {
              const Vec2 d = pb[k + 1] - pb[k];
              const double l2 = d.squaredNorm();
              const double f = l2 > 0 ? std::clamp((q - pb[k]).dot(d) / l2, 0.0, 1.0) : 0.0;
              best = std::min(best, (q - (pb[k] + f * d)).norm());
            }
            return best;
          };
          const double limit = 1e-6 * std::max(1.0, (pa.back() - pa.front()).norm());
          const bool before = t - step >= t0 && near_b(a.point(t - step)) <= limit;
          const bool after = t + step <= t1 && near_b(a.point(t + step)) <= limit;
          if (before || after) continue;
        }
      }
      bool dup = false;
      for (const Crossing& c : found) {
        if (std::abs(c.t - t) < 1e-7 * std::max(1.0, t1 - t0) && std::abs(c.s - s) < 1e-7 * std::max(1.0, s1 - s0)) dup = true;
      }
      if (!dup) found.push_back({t, s});
    }
  }
  std::sort(found.begin(), found.end(), [](const Crossing& x, const Crossing& y) { return x.t < y.t; });
  return found;
}

}  // namespace csgtile::kernel::detail
