// Marching surface–surface intersection: seeds from a lattice, predictor along n_a × n_b,
// Newton corrector on both surfaces and a plane across the step, chordal error control.

#include "boolean/marching.h"

#include "boolean/cell_hash.h"
#include "boolean/pcurve_fit.h"

#include <Eigen/LU>
#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <unordered_map>

namespace csgtile::kernel::detail {

namespace {

using Vector4d = Eigen::Vector4d;

// Limits of the tracer (not geometric tolerances: counts and ratios).
constexpr int kLatticeCells = 16;         // lattice spacing = region diagonal / this
constexpr int kMaxLattice = 17;           // points per axis at most
constexpr int kPullIterations = 40;       // minimum-norm Newton steps for a seed
constexpr int kCorrectIterations = 12;    // corrector steps per march step
constexpr int kMaxSteps = 50000;          // per branch direction
constexpr double kMaxTurn = 0.9659;       // cos 15°: largest tangent turn in one step
constexpr double kNewtonFraction = 1e-3;  // Newton stops at this fraction of the tolerance
constexpr double kTangentSine = 1e-7;     // |n_a × n_b| below this: tangent surfaces

class Pair {
 public:
  Pair(const Surface& a, const Surface& b) : a_(a), b_(b) {}

  Vec3 pa(const Vector4d& w) const { return a_.point(w[0], w[1]); }
  Vec3 pb(const Vector4d& w) const { return b_.point(w[2], w[3]); }

  Eigen::Matrix<double, 3, 4> jacobian(const Vector4d& w) const {
    Eigen::Matrix<double, 3, 4> j;
    j.col(0) = a_.du(w[0], w[1]);
    j.col(1) = a_.dv(w[0], w[1]);
    j.col(2) = -b_.du(w[2], w[3]);
    j.col(3) = -b_.dv(w[2], w[3]);
    return j;
  }

  /// Unit tangent n_a × n_b (its sign as the normals give it); zero where tangent.
  Vec3 tangent(const Vector4d& w) const {
    const Vec3 t = a_.normal(w[0], w[1]).cross(b_.normal(w[2], w[3]));
    const double n = t.norm();
    return n < kTangentSine ? Vec3::Zero() : Vec3(t / n);
  }

  /// Parameter velocity for moving along `t` (unit) at w: least squares on each surface.
  Vector4d velocity(const Vector4d& w, const Vec3& t) const {
    Vector4d out;
    for (int s = 0; s < 2; ++s) {
      const Surface& surface = s == 0 ? a_ : b_;
      const double u = w[2 * s], v = w[2 * s + 1];
      Eigen::Matrix<double, 3, 2> m;
      m.col(0) = surface.du(u, v);
      m.col(1) = surface.dv(u, v);
      const Eigen::Vector2d x = m.colPivHouseholderQr().solve(t);
      out[2 * s] = x[0];
      out[2 * s + 1] = x[1];
    }
    return out;
  }

  /// Pulls w onto the intersection by minimum-norm Newton steps (3 equations, 4 unknowns).
  bool pull(Vector4d& w, double eps) const {
    for (int i = 0; i < kPullIterations; ++i) {
      const Vec3 r = pa(w) - pb(w);
      if (!std::isfinite(r.norm())) return false;
      if (r.norm() <= eps) return true;
      const Vector4d step = jacobian(w).completeOrthogonalDecomposition().solve(-r);
      if (!step.allFinite()) return false;
      w += step;
    }
    return (pa(w) - pb(w)).norm() <= eps;
  }

  /// Newton on both surfaces and the plane through `x` across `t`, from w.
  bool correct(Vector4d& w, const Vec3& x, const Vec3& t, double eps) const {
    for (int i = 0; i < kCorrectIterations; ++i) {
      const Vec3 sa = pa(w);
      const Vec3 r = sa - pb(w);
      const double plane = t.dot(sa - x);
      if (r.norm() <= eps && std::abs(plane) <= eps) return true;
      Eigen::Matrix4d j;
      j.topRows<3>() = jacobian(w);
      j.row(3) << t.dot(a_.du(w[0], w[1])), t.dot(a_.dv(w[0], w[1])), 0.0, 0.0;
      Vector4d f;
      f << r, plane;
      const Vector4d step = j.fullPivLu().solve(-f);
      if (!step.allFinite()) return false;
      w += step;
    }
    const Vec3 sa = pa(w);
    return (sa - pb(w)).norm() <= eps && std::abs(t.dot(sa - x)) <= eps;
  }

  double u_period_a() const { return a_.u_period(); }
  double v_period_a() const { return a_.v_period(); }
  double u_period_b() const { return b_.u_period(); }
  double v_period_b() const { return b_.v_period(); }

 private:
  const Surface& a_;
  const Surface& b_;
};

/// Traced points of all branches so far, hashed by cell, to drop seeds on known branches.
class PointHash {
 public:
  explicit PointHash(double cell) : cell_(cell) {}
  void add(const Vec3& p) { cells_[key(p)].push_back(p); }
  bool near(const Vec3& p, double distance) const {
    const auto c = coords(p);
    for (long long dx = -1; dx <= 1; ++dx) {
      for (long long dy = -1; dy <= 1; ++dy) {
        for (long long dz = -1; dz <= 1; ++dz) {
          auto it = cells_.find(hash(c[0] + dx, c[1] + dy, c[2] + dz));
          if (it == cells_.end()) continue;
          for (const Vec3& q : it->second) {
            if ((q - p).norm() <= distance) return true;
          }
        }
      }
    }
    return false;
  }

 private:
  std::array<long long, 3> coords(const Vec3& p) const {
    return {static_cast<long long>(std::floor(p.x() / cell_)),
            static_cast<long long>(std::floor(p.y() / cell_)),
            static_cast<long long>(std::floor(p.z() / cell_))};
  }
  static long long hash(long long x, long long y, long long z) { return cell_hash(x, y, z); }
  long long key(const Vec3& p) const {
    const auto c = coords(p);
    return hash(c[0], c[1], c[2]);
  }
  double cell_;
  std::unordered_map<long long, std::vector<Vec3>> cells_;
};

struct Branch {
  std::vector<Vector4d> params;
  bool closed = false;
  double deviation = 0.0;
  double longest_step = 0.0;
};

class Tracer {
 public:
  Tracer(const Pair& pair, const BoundingBox& region, double tolerance, double sag)
      : pair_(pair), region_(region), eps_(tolerance * kNewtonFraction), sag_(sag) {
    const double diag = region.size().norm();
    h_max_ = diag / 20.0;
    h_min_ = std::max(sag * 1e-3, diag * 1e-9);
  }

  /// Marches from `start` along sign·tangent; appends to `out` (start excluded).
  /// Returns false with `reason` on a tangency or a step that cannot be made.
  bool march(const Vector4d& start, double sign, Branch& out, std::string& reason) const {
    Vector4d w = start;
    Vec3 x = pair_.pa(w);
    const Vec3 x_start = x;
    Vec3 t = sign * pair_.tangent(w);
    if (t.isZero()) {
      reason = "tangent surfaces at the start of a branch";
      return false;
    }
    double h = h_max_ / 4;
    double traveled = 0.0;
    for (int step = 0; step < kMaxSteps; ++step) {
      Vector4d next = w + h * pair_.velocity(w, t);
      const Vec3 x_pred = x + h * t;
      bool accepted = false;
      Vec3 x_next, t_next;
      double deviation = 0.0;
      if (pair_.correct(next, x_pred, t, eps_)) {
        x_next = pair_.pa(next);
        t_next = pair_.tangent(next);
        if (t_next.isZero()) {
          reason = "tangent surfaces along a branch";
          return false;
        }
        if (t_next.dot(t) < 0) t_next = -t_next;
        if (t_next.dot(t) >= kMaxTurn) {
          deviation = chord_deviation(w, next, x, x_next);
          accepted = deviation <= sag_;
        }
      }
      if (!accepted) {
        h *= 0.5;
        if (h < h_min_) {
          reason = "the step fell below its minimum (a singular point of the intersection)";
          return false;
        }
        continue;
      }
      const double length = (x_next - x).norm();
      // Closed: this chord passes the start again after a real journey.
      if (traveled > 2.0 * length &&
          distance_to_segment(x_start, x, x_next) <= 0.5 * length + sag_) {
        Vector4d closing = start;
        for (int k = 0; k < 4; ++k) closing[k] = nearest_periodic(start[k], next[k], period(k));
        const double closing_deviation = chord_deviation(w, closing, x, x_start);
        if (closing_deviation > sag_) {
          // Back at the start in space but not in parameters: the branch crossed a point where
          // a surface's parameters are singular (a sphere's pole, a cone's apex).
          const double jump = (closing - next).norm(), step_size = (next - w).norm();
          if (jump > 10.0 * step_size || (x_start - x).norm() <= 4 * h_min_) {
            reason =
                "the intersection passes a singular point of a surface's parameters (pole or apex)";
            return false;
          }
          // Approach the start in shorter steps.
          h = std::max(0.5 * (x_start - x).norm(), 2 * h_min_);
          continue;
        }
        out.params.push_back(closing);
        out.closed = true;
        out.deviation = std::max(out.deviation, closing_deviation);
        out.longest_step = std::max(out.longest_step, (x_start - x).norm());
        return true;
      }
      out.params.push_back(next);
      out.deviation = std::max(out.deviation, deviation);
      out.longest_step = std::max(out.longest_step, length);
      traveled += length;
      if (!region_.contains(x_next)) return true;  // left the region: the end is outside
      // Next step from the curvature seen over this one.
      const double turn = (t_next - t).norm();
      double h_next = std::min(h_max_, 1.5 * h);
      if (turn > 0) h_next = std::min(h_next, 0.9 * std::sqrt(8.0 * sag_ * length / turn));
      h = std::max(h_next, 2 * h_min_);
      w = next;
      x = x_next;
      t = t_next;
    }
    reason = "a branch did not end within the step limit";
    return false;
  }

  double period(int k) const {
    switch (k) {
      case 0:
        return pair_.u_period_a();
      case 1:
        return pair_.v_period_a();
      case 2:
        return pair_.u_period_b();
      default:
        return pair_.v_period_b();
    }
  }

 private:
  // Distance from the exact curve and from each pcurve segment's image to the chord, at the
  // middle of the step (where it is largest for smooth curves).
  double chord_deviation(const Vector4d& w0, const Vector4d& w1, const Vec3& x0,
                         const Vec3& x1) const {
    const Vector4d mid = 0.5 * (w0 + w1);
    const Vec3 chord = 0.5 * (x0 + x1);
    double d = std::max((pair_.pa(mid) - chord).norm(), (pair_.pb(mid) - chord).norm());
    Vector4d exact = mid;
    const Vec3 along = (x1 - x0).normalized();
    if (pair_.correct(exact, chord, along, eps_)) d = std::max(d, (pair_.pa(exact) - chord).norm());
    return d;
  }

  static double distance_to_segment(const Vec3& p, const Vec3& a, const Vec3& b) {
    const Vec3 ab = b - a;
    const double len2 = ab.squaredNorm();
    const double s = len2 > 0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
    return (a + s * ab - p).norm();
  }

  const Pair& pair_;
  BoundingBox region_;
  double eps_, sag_, h_max_, h_min_;
};

}  // namespace

MarchResult march_intersection(const Surface& a, const Surface& b, const BoundingBox& region,
                               double tolerance, double sag) {
  MarchResult result;
  if (region.empty()) return result;
  const Pair pair(a, b);
  const Tracer tracer(pair, region, tolerance, sag);
  const double eps = tolerance * kNewtonFraction;
  const Vec3 extent = region.size();
  const double diag = extent.norm();
  const double cell = diag / kLatticeCells;
  int n[3];
  for (int k = 0; k < 3; ++k) {
    n[k] = std::clamp(static_cast<int>(std::ceil(extent[k] / cell)) + 1, 2, kMaxLattice);
  }
  double spacing_max = 0.0;
  for (int k = 0; k < 3; ++k) spacing_max = std::max(spacing_max, extent[k] / (n[k] - 1));
  const double reach = 0.5 * std::sqrt(3.0) * spacing_max * 1.01;
  PointHash traced(diag / kLatticeCells);
  double spacing = diag / 20.0;  // largest chord of the traced branches (for dropping seeds)
  for (int i = 0; i < n[0]; ++i) {
    for (int j = 0; j < n[1]; ++j) {
      for (int k = 0; k < n[2]; ++k) {
        const Vec3 p = region.min + Vec3(extent.x() * i / (n[0] - 1), extent.y() * j / (n[1] - 1),
                                         extent.z() * k / (n[2] - 1));
        const Vec2 ua = a.closest_parameters(p), ub = b.closest_parameters(p);
        // Every point of the region is within half a lattice diagonal of a lattice point, so
        // a lattice point farther than that from either surface seeds nothing new.
        if ((a.point(ua.x(), ua.y()) - p).norm() > reach ||
            (b.point(ub.x(), ub.y()) - p).norm() > reach) {
          continue;
        }
        Vector4d w(ua.x(), ua.y(), ub.x(), ub.y());
        if (!pair.pull(w, eps)) continue;
        // Canonical parameters (Newton may land on an equivalent pair, e.g. a sphere's v past
        // a pole with u turned by π): marching then stays continuous from them.
        const Vec2 ca = a.closest_parameters(pair.pa(w)), cb = b.closest_parameters(pair.pb(w));
        w = Vector4d(ca.x(), ca.y(), cb.x(), cb.y());
        if (!pair.pull(w, eps)) continue;
        const Vec3 x = pair.pa(w);
        if (!region.contains(x)) continue;
        if (traced.near(x, 0.5 * spacing + 10 * sag)) continue;
        Branch forward, backward;
        forward.params.push_back(w);
        if (!tracer.march(w, 1.0, forward, result.reason)) {
          result.ok = false;
          return result;
        }
        if (!forward.closed && !tracer.march(w, -1.0, backward, result.reason)) {
          result.ok = false;
          return result;
        }
        // Backward points reversed, then the forward ones (which start at the seed).
        std::vector<Vector4d> params(backward.params.rbegin(), backward.params.rend());
        params.insert(params.end(), forward.params.begin(), forward.params.end());
        MarchedCurve curve;
        curve.closed = forward.closed;
        curve.deviation = std::max(forward.deviation, backward.deviation);
        for (const Vector4d& q : params) {
          curve.points.push_back(pair.pa(q));
          curve.uv_a.emplace_back(q[0], q[1]);
          curve.uv_b.emplace_back(q[2], q[3]);
        }
        if (curve.closed) curve.points.back() = curve.points.front();
        if (curve.points.size() < 2) continue;
        for (const Vec3& q : curve.points) traced.add(q);
        spacing = std::max({spacing, forward.longest_step, backward.longest_step});
        result.curves.push_back(std::move(curve));
      }
    }
  }
  return result;
}

std::optional<MarchedCurve> sample_section(const Curve& c, double t0, double t1, const Surface& a,
                                           const Surface& b, double sag) {
  constexpr std::size_t kMaxPoints = 100000;
  constexpr int kInitialSegments = 32;
  std::vector<double> ts;
  for (int i = 0; i <= kInitialSegments; ++i) ts.push_back(t0 + (t1 - t0) * i / kInitialSegments);
  MarchedCurve out;
  auto parameters = [&](const Surface& s, std::vector<Vec2>& uv) {
    uv.clear();
    for (std::size_t i = 0; i < ts.size(); ++i) {
      Vec2 q = s.closest_parameters(c.point(ts[i]));
      if (i > 0) {
        q.x() = nearest_periodic(q.x(), uv.back().x(), s.u_period());
        q.y() = nearest_periodic(q.y(), uv.back().y(), s.v_period());
      }
      uv.push_back(q);
    }
  };
  for (;;) {
    parameters(a, out.uv_a);
    parameters(b, out.uv_b);
    std::vector<double> refined{ts.front()};
    double worst = 0.0;
    bool split = false;
    for (std::size_t i = 0; i + 1 < ts.size(); ++i) {
      const Vec3 p0 = c.point(ts[i]), p1 = c.point(ts[i + 1]);
      const Vec3 chord = 0.5 * (p0 + p1);
      const Vec2 ma = 0.5 * (out.uv_a[i] + out.uv_a[i + 1]),
                 mb = 0.5 * (out.uv_b[i] + out.uv_b[i + 1]);
      const double d = std::max({(c.point(0.5 * (ts[i] + ts[i + 1])) - chord).norm(),
                                 (a.point(ma.x(), ma.y()) - chord).norm(),
                                 (b.point(mb.x(), mb.y()) - chord).norm()});
      if (d > sag) {
        refined.push_back(0.5 * (ts[i] + ts[i + 1]));
        split = true;
      } else {
        worst = std::max(worst, d);
      }
      refined.push_back(ts[i + 1]);
    }
    ts = std::move(refined);
    if (!split) {
      out.deviation = worst;
      break;
    }
    if (ts.size() > kMaxPoints) return std::nullopt;
  }
  for (double t : ts) out.points.push_back(c.point(t));
  out.closed = (out.points.front() - out.points.back()).norm() <= sag;
  if (out.closed) out.points.back() = out.points.front();
  return out;
}

}  // namespace csgtile::kernel::detail
