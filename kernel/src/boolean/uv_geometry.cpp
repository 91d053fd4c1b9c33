#include "boolean/uv_geometry.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "boolean/tolerance.h"
#include "csgtile/kernel/polygon2d.h"
#include "predicates/predicates.h"

namespace csgtile::kernel::detail {

namespace {

// Parameters of sample_use's points, in the use's direction.
std::vector<double> sample_parameters(const BModel& m, const BUse& use, int samples) {
  const BEdge& e = m.edges[static_cast<std::size_t>(use.edge)];
  // Lines need their ends only; polylines (traced sections) at least one sample per segment.
  const int n = use.pcurve->kind() == Curve2dKind::Line ? 1
                : use.pcurve->kind() == Curve2dKind::Polyline
                    ? std::max(samples, static_cast<int>(std::ceil(std::abs(e.t1 - e.t0))))
                    : samples;
  std::vector<double> out;
  out.reserve(static_cast<std::size_t>(n) + 1);
  for (int i = 0; i <= n; ++i) {
    const double f = static_cast<double>(i) / n;
    out.push_back(use.forward ? e.t0 + (e.t1 - e.t0) * f : e.t1 - (e.t1 - e.t0) * f);
  }
  return out;
}

// Side of `uv` with respect to the arc (walked t0 → t1): +1 left, −1 right, 0 within
// `margin` of it; nullopt when the arc's nearest point is one of its ends (the point is then
// not between the chord and the arc, whose every point projects inside the short arc). The
// nearest point by golden-section search (the point is within the arc's bulge of its chord,
// where the distance has one minimum on the arc).
std::optional<int> arc_side(const FacePolygon::Arc& arc, const Vec2& uv, double margin) {
  constexpr double kGolden = 0.6180339887498949;
  constexpr int kSearchSteps = 80;
  constexpr double kEndFraction = 1e-9;  // of the arc's span: the search ended at an end
  double lo = std::min(arc.t0, arc.t1), hi = std::max(arc.t0, arc.t1);
  const double first = lo, last = hi;
  auto distance = [&](double t) { return (arc.curve->point(t) - uv).squaredNorm(); };
  double x1 = hi - kGolden * (hi - lo), x2 = lo + kGolden * (hi - lo);
  double d1 = distance(x1), d2 = distance(x2);
  for (int i = 0; i < kSearchSteps && hi - lo > 0; ++i) {
    if (d1 <= d2) {
      hi = x2;
      x2 = x1;
      d2 = d1;
      x1 = hi - kGolden * (hi - lo);
      d1 = distance(x1);
    } else {
      lo = x1;
      x1 = x2;
      d1 = d2;
      x2 = lo + kGolden * (hi - lo);
      d2 = distance(x2);
    }
  }
  const double t = 0.5 * (lo + hi);
  if (t <= first + kEndFraction * (last - first) || t >= last - kEndFraction * (last - first))
    return std::nullopt;
  const Vec2 offset = uv - arc.curve->point(t);
  if (offset.norm() <= margin) return 0;
  const Vec2 tangent = arc.curve->derivative(t) * (arc.t1 >= arc.t0 ? 1.0 : -1.0);
  return predicates::cross_sign(tangent, offset);
}

}  // namespace

std::vector<Vec2> sample_use(const BModel& m, const BUse& use, int samples) {
  std::vector<Vec2> out;
  for (const double t : sample_parameters(m, use, samples)) out.push_back(use.pcurve->point(t));
  return out;
}

namespace {

void add_loop(FacePolygon& p, const BModel& m, const BLoop& loop) {
  std::vector<Vec2> pts;
  std::vector<FacePolygon::Arc> arcs;
  for (const BUse& use : loop) {
    const std::vector<double> ts = sample_parameters(m, use, 48);
    const bool straight =
        use.pcurve->kind() == Curve2dKind::Line || use.pcurve->kind() == Curve2dKind::Polyline;
    for (std::size_t i = 0; i + 1 < ts.size(); ++i) {
      const Vec2 a = use.pcurve->point(ts[i]), b = use.pcurve->point(ts[i + 1]);
      pts.push_back(a);
      FacePolygon::Arc arc;
      if (!straight) {
        // The bulge seen at three points, doubled: the arcs are short stretches of smooth
        // curves, whose distance from the chord is largest near the middle.
        for (const double f : {0.25, 0.5, 0.75}) {
          arc.bulge =
              std::max(arc.bulge,
                       segment_distance(use.pcurve->point(ts[i] + f * (ts[i + 1] - ts[i])), a, b));
        }
        arc.bulge *= kArcBulgeSafety;
        arc.curve = use.pcurve;
        arc.t0 = ts[i];
        arc.t1 = ts[i + 1];
      }
      arcs.push_back(std::move(arc));
    }
  }
  for (const Vec2& q : pts) {
    p.min = p.min.cwiseMin(q);
    p.max = p.max.cwiseMax(q);
  }
  p.loops.push_back(std::move(pts));
  p.arcs.push_back(std::move(arcs));
}

}  // namespace

FacePolygon face_polygon(const BModel& m, const BFace& face, const std::vector<BLoop>& loops) {
  FacePolygon p;
  p.u_period = face.surface->u_period();
  p.v_period = face.surface->v_period();
  p.min = Vec2::Constant(std::numeric_limits<double>::infinity());
  p.max = -p.min;
  for (const BLoop& loop : loops) add_loop(p, m, loop);
  return p;
}

FacePolygon face_polygon(const BModel& m, const BFace& face) {
  return face_polygon(m, face, face.loops);
}

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
  // Within the margin is a coincidence (tolerance); outside it the side is decided exactly.
  if (margin > 0.0 && boundary_distance(uv) <= margin) return std::nullopt;
  bool in = false;
  switch (predicates::locate_in_polygon(uv, loops)) {
    case predicates::PolygonLocation::Inside:
      in = true;
      break;
    case predicates::PolygonLocation::Outside:
      in = false;
      break;
    case predicates::PolygonLocation::OnBoundary:
      return std::nullopt;
  }
  // The sides of curved pcurves are chords: between a chord and its arc the face and the
  // polygon disagree (a section chord of a cap disc, shorter than the sampling, lies there).
  for (std::size_t l = 0; l < arcs.size(); ++l) {
    const std::vector<Vec2>& loop = loops[l];
    for (std::size_t i = 0; i < arcs[l].size(); ++i) {
      const Arc& arc = arcs[l][i];
      if (arc.bulge <= 0) continue;
      const Vec2 &a = loop[i], &b = loop[(i + 1) % loop.size()];
      if (segment_distance(uv, a, b) > arc.bulge) continue;
      const std::optional<int> curve_side = arc_side(arc, uv, margin);
      if (!curve_side) continue;
      if (*curve_side == 0) return std::nullopt;
      if (*curve_side != predicates::orient2d(a, b, uv)) in = !in;
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

namespace {

// intersect_pcurves' samples of a curve: polylines (traced sections) at least once per segment.
int crossing_samples(const Curve2d& c, double span) {
  if (c.kind() == Curve2dKind::Line) return 1;
  if (c.kind() == Curve2dKind::Polyline) {
    return std::max(kCrossingSamples, static_cast<int>(std::ceil(std::abs(span))));
  }
  return kCrossingSamples;
}

}  // namespace

std::vector<Vec2> crossing_points(const Curve2d& c, double t0, double t1) {
  const int n = crossing_samples(c, t1 - t0);
  std::vector<Vec2> out;
  out.reserve(static_cast<std::size_t>(n) + 1);
  for (int i = 0; i <= n; ++i) out.push_back(c.point(t0 + (t1 - t0) * i / n));
  return out;
}

CrossingBox crossing_box(const Curve2d& c, double t0, double t1) {
  return crossing_box(c, t0, t1, crossing_points(c, t0, t1));
}

CrossingBox crossing_box(const Curve2d& c, double t0, double t1, const std::vector<Vec2>& points) {
  CrossingBox box;
  box.min = box.max = points.front();
  double longest = 0;
  for (std::size_t i = 1; i < points.size(); ++i) {
    box.min = box.min.cwiseMin(points[i]);
    box.max = box.max.cwiseMax(points[i]);
    longest = std::max(longest, (points[i] - points[i - 1]).norm());
  }
  // Candidate segment boxes grow by kCrossingBoxGrowth of their length; a line's near miss
  // at an end is accepted within the parameter slack (in (u, v): times its speed).
  box.reach = kCrossingBoxGrowth * longest;
  box.line = c.kind() == Curve2dKind::Line;
  if (box.line) box.reach += param_slack(std::abs(t1 - t0)) * c.derivative(t0).norm();
  return box;
}

bool crossing_boxes_apart(const CrossingBox& a, const CrossingBox& b, const Vec2& shift_b,
                          double tolerance) {
  // A shifted copy's points are the shifted points up to rounding: pad far above it.
  constexpr double kRoundingPad = 1e-9;
  if (a.line && b.line) return false;
  const double magnitude = std::max({a.min.cwiseAbs().maxCoeff(), a.max.cwiseAbs().maxCoeff(),
                                     b.min.cwiseAbs().maxCoeff(), b.max.cwiseAbs().maxCoeff()}) +
                           shift_b.cwiseAbs().maxCoeff();
  const double gap = tolerance + a.reach + b.reach + kRoundingPad * (1.0 + magnitude);
  for (int k = 0; k < 2; ++k) {
    if (a.min[k] - gap > b.max[k] + shift_b[k] || b.min[k] + shift_b[k] - gap > a.max[k])
      return true;
  }
  return false;
}

std::vector<Crossing> intersect_pcurves(const Curve2d& a, double t0, double t1, const Curve2d& b,
                                        double s0, double s1, double tolerance) {
  return intersect_pcurves(a, t0, t1, crossing_points(a, t0, t1), b, s0, s1, tolerance);
}

std::vector<Crossing> intersect_pcurves(const Curve2d& a, double t0, double t1,
                                        const std::vector<Vec2>& a_points, const Curve2d& b,
                                        double s0, double s1, double tolerance) {
  // Below this a Newton determinant is singular (a division by it could overflow).
  constexpr double kSingular = 1e-300;
  constexpr int kNewtonIterations = 40;
  const auto& samples_of = crossing_samples;
  const int na = samples_of(a, t1 - t0), nb = samples_of(b, s1 - s0);
  const std::vector<Vec2>& pa = a_points;  // crossing_points(a, t0, t1)
  std::vector<Vec2> pb;
  pb.reserve(static_cast<std::size_t>(nb) + 1);
  for (int i = 0; i <= nb; ++i) pb.push_back(b.point(s0 + (s1 - s0) * i / nb));
  std::vector<Crossing> found;
  const double pad_t = param_slack(std::abs(t1 - t0)), pad_s = param_slack(std::abs(s1 - s0));
  // Keeps the meeting point (t, s) unless it lies outside the ranges (by more than the
  // parameter slack; `exact`: known to be on both), is where the curves run along each
  // other, or was found already.
  auto accept = [&](double t, double s, bool exact) {
    if (!exact && (t < t0 - pad_t || t > t1 + pad_t || s < s0 - pad_s || s > s1 + pad_s)) return;
    t = std::clamp(t, t0, t1);
    s = std::clamp(s, s0, s1);
    // Curves that run along each other (overlapping boundaries of coincident faces) do
    // not cross: their shared stretch is handled by vertex splits, not crossings.
    const Vec2 ta = a.derivative(t), tb = b.derivative(s);
    const double cross = std::abs(ta.x() * tb.y() - ta.y() * tb.x());
    if (cross <= kPcurveTangentSine * ta.norm() * tb.norm()) {
      const double step = kAlongProbeStep * (t1 - t0);
      auto near_b = [&](const Vec2& q) {
        double best = std::numeric_limits<double>::infinity();
        for (int k = 0; k < nb; ++k) best = std::min(best, segment_distance(q, pb[k], pb[k + 1]));
        return best;
      };
      const double limit = kAlongUvRelative * std::max(1.0, (pa.back() - pa.front()).norm());
      const bool before = t - step >= t0 && near_b(a.point(t - step)) <= limit;
      const bool after = t + step <= t1 && near_b(a.point(t + step)) <= limit;
      if (before || after) return;
    }
    for (const Crossing& c : found) {
      if (std::abs(c.t - t) < kCrossingMergeRelative * std::max(1.0, t1 - t0) &&
          std::abs(c.s - s) < kCrossingMergeRelative * std::max(1.0, s1 - s0)) {
        return;
      }
    }
    found.push_back({t, s});
  };
  if (a.kind() == Curve2dKind::Line && b.kind() == Curve2dKind::Line) {
    // Two straight pieces: the exact segment predicates decide whether they meet; only a
    // near miss at an end (the pieces of one boundary do not quite join) is left to the
    // parameter slack.
    const Vec2 a0 = a.point(t0), a1 = a.point(t1), b0 = b.point(s0), b1 = b.point(s1);
    // Parallel pieces never cross (a shared stretch is handled by vertex splits).
    if (predicates::cross_sign(a0, a1, b0, b1) == 0) return found;
    const Vec2 da = a1 - a0, db = b1 - b0, w = b0 - a0;
    const double den = da.x() * db.y() - da.y() * db.x();
    if (den == 0.0) return found;
    double fa = (w.x() * db.y() - w.y() * db.x()) / den;
    double fb = (w.x() * da.y() - w.y() * da.x()) / den;
    const bool meet =
        predicates::classify_segments(a0, a1, b0, b1) != predicates::SegmentRelation::Disjoint;
    if (meet) {
      fa = std::clamp(fa, 0.0, 1.0);
      fb = std::clamp(fb, 0.0, 1.0);
    }
    accept(t0 + (t1 - t0) * fa, s0 + (s1 - s0) * fb, meet);
    return found;
  }
  // Candidate pairs: segments whose boxes meet (grown by a margin for curvature). b's
  // segments are also taken in blocks, whose box holds theirs and whose growth is their
  // largest: a block that a's segment misses holds no candidate (the same pairs, in the same
  // order, with fewer tests).
  constexpr int kBlock = 8;
  struct Block {
    Vec2 min, max;
    double growth = 0;
  };
  std::vector<Block> blocks;
  for (int first = 0; first < nb; first += kBlock) {
    Block block{pb[first], pb[first], 0.0};
    for (int j = first; j < std::min(nb, first + kBlock); ++j) {
      block.min = block.min.cwiseMin(pb[j + 1]);
      block.max = block.max.cwiseMax(pb[j + 1]);
      block.growth = std::max(block.growth, kCrossingBoxGrowth * (pb[j + 1] - pb[j]).norm());
    }
    blocks.push_back(block);
  }
  for (int i = 0; i < na; ++i) {
    const Vec2 amin = pa[i].cwiseMin(pa[i + 1]), amax = pa[i].cwiseMax(pa[i + 1]);
    const double grow_a = kCrossingBoxGrowth * (pa[i + 1] - pa[i]).norm() + tolerance;
    for (int j = 0; j < nb; ++j) {
      if (j % kBlock == 0) {
        const Block& block = blocks[static_cast<std::size_t>(j / kBlock)];
        const double grow = grow_a + block.growth;
        if ((amin.array() - grow > block.max.array()).any() ||
            (block.min.array() - grow > amax.array()).any()) {
          j += kBlock - 1;
          continue;
        }
      }
      const Vec2 bmin = pb[j].cwiseMin(pb[j + 1]), bmax = pb[j].cwiseMax(pb[j + 1]);
      const double grow = grow_a + kCrossingBoxGrowth * (pb[j + 1] - pb[j]).norm();
      if ((amin.array() - grow > bmax.array()).any() ||
          (bmin.array() - grow > amax.array()).any()) {
        continue;
      }
      // Start from the segments' own intersection (or their midpoints) and refine.
      const Vec2 da = pa[i + 1] - pa[i], db = pb[j + 1] - pb[j];
      const double den = da.x() * db.y() - da.y() * db.x();
      double fa = 0.5, fb = 0.5;
      if (den != 0.0) {
        const Vec2 w = pb[j] - pa[i];
        fa = std::clamp((w.x() * db.y() - w.y() * db.x()) / den, 0.0, 1.0);
        fb = std::clamp((w.x() * da.y() - w.y() * da.x()) / den, 0.0, 1.0);
      }
      double t = t0 + (t1 - t0) * (i + fa) / na;
      double s = s0 + (s1 - s0) * (j + fb) / nb;
      bool converged = false;
      for (int it = 0; it < kNewtonIterations; ++it) {
        const Vec2 f = a.point(t) - b.point(s);
        if (f.norm() <= tolerance * kNewtonConvergedFraction) {
          converged = true;
          break;
        }
        const Vec2 ja = a.derivative(t), jb = -b.derivative(s);
        const double det = ja.x() * jb.y() - ja.y() * jb.x();
        if (std::abs(det) < kSingular) break;
        const double dt = (f.x() * jb.y() - f.y() * jb.x()) / det;
        const double ds = (ja.x() * f.y() - ja.y() * f.x()) / det;
        t -= dt;
        s -= ds;
        if (std::abs(dt) + std::abs(ds) < kNewtonStall * (1 + std::abs(t) + std::abs(s))) {
          converged = (a.point(t) - b.point(s)).norm() <= tolerance;
          break;
        }
      }
      if (!std::isfinite(t) || !std::isfinite(s)) continue;
      if (!converged) {
        // Tangential contact converges slowly: accept a close approach.
        if (!((a.point(t) - b.point(s)).norm() <= tolerance)) continue;
      }
      accept(t, s, false);
    }
  }
  std::sort(found.begin(), found.end(),
            [](const Crossing& x, const Crossing& y) { return x.t < y.t; });
  // A tangential contact comes back as a cluster of crossings along the stretch where the
  // curves stay within the tolerance of each other (Newton lands anywhere on it): within the
  // tolerance that stretch is one contact point, at the middle of the cluster.
  auto together = [&](const Crossing& x, const Crossing& y) {
    for (const double f : {0.25, 0.5, 0.75}) {
      const Vec2 p = a.point(x.t + f * (y.t - x.t)), q = b.point(x.s + f * (y.s - x.s));
      if (!((p - q).norm() <= tolerance)) return false;
    }
    return true;
  };
  std::vector<Crossing> contacts;
  for (std::size_t i = 0; i < found.size();) {
    std::size_t j = i;
    while (j + 1 < found.size() && together(found[i], found[j + 1])) ++j;
    contacts.push_back({0.5 * (found[i].t + found[j].t), 0.5 * (found[i].s + found[j].s)});
    i = j + 1;
  }
  return contacts;
}

}  // namespace csgtile::kernel::detail
