#include "csgtile/kernel/mass_properties.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <optional>
#include <type_traits>
#include <utility>
#include <vector>

#include "csgtile/kernel/explorer.h"
#include "geometry/geometry_internal.h"
#include "mass/mass_internal.h"

namespace csgtile::kernel {

namespace {

// Integrands per unit (u, v) area, N = S_u × S_v in world coordinates (un-normalised).
// 0: area |N|, 1: volume p·N / 3, 2..4: first moments p_i² N_i / 2.
using Moments = std::array<double, 5>;
// The volume integrand alone (solid_volume; planes and cylinders take the closed forms of
// FaceIntegrator::inner, the rest the same Gauss sums as the full Moments).
using VolumeMoment = std::array<double, 1>;

constexpr double kAngularPanel = std::numbers::pi / 4;

template <std::size_t N>
std::array<double, N>& operator+=(std::array<double, N>& a, const std::array<double, N>& b) {
  for (std::size_t i = 0; i < N; ++i) a[i] += b[i];
  return a;
}
template <std::size_t N>
std::array<double, N> scaled(const std::array<double, N>& m, double s) {
  std::array<double, N> out{};
  for (std::size_t i = 0; i < N; ++i) out[i] = m[i] * s;
  return out;
}

// Point and partial derivatives of a surface in world coordinates. Planes and cylinders (most
// faces of city models) are evaluated here with the very expressions of their classes
// (geometry/surface_quadrics.cpp), one cosine/sine pair per point; a face in the identity
// location skips the transform (identical values). Others go through the virtual calls.
struct SurfacePoint {
  Vec3 p, su, sv;  // point, ∂/∂u, ∂/∂v
};

class SurfaceEvaluator {
 public:
  SurfaceEvaluator(const Surface& surface, const Location& location)
      : surface_(surface), location_(location), identity_(location.is_identity()) {
    if (surface.kind() == SurfaceKind::Plane) {
      kind_ = Kind::Plane;
      frame_ = static_cast<const PlaneSurface&>(surface).frame();
    } else if (surface.kind() == SurfaceKind::Cylinder) {
      kind_ = Kind::Cylinder;
      frame_ = static_cast<const CylinderSurface&>(surface).frame();
      radius_ = static_cast<const CylinderSurface&>(surface).radius();
    }
  }

  bool plane() const { return kind_ == Kind::Plane; }
  bool cylinder() const { return kind_ == Kind::Cylinder; }

  // A cylinder's point at (u, v) from c = cos u, s = sin u.
  SurfacePoint evaluate_cylinder(double c, double s, double v) const {
    const Vec3 radial = c * frame_.x + s * frame_.y;
    const Vec3 radial_derivative = -s * frame_.x + c * frame_.y;
    return placed(
        {frame_.origin + radius_ * radial + v * frame_.z, radius_ * radial_derivative, frame_.z});
  }

  SurfacePoint evaluate(double u, double v) const {
    if (kind_ == Kind::Plane)
      return placed({frame_.origin + u * frame_.x + v * frame_.y, frame_.x, frame_.y});
    if (kind_ == Kind::Cylinder) return evaluate_cylinder(std::cos(u), std::sin(u), v);
    return placed({surface_.point(u, v), surface_.du(u, v), surface_.dv(u, v)});
  }

 private:
  enum class Kind { Plane, Cylinder, Other };
  SurfacePoint placed(const SurfacePoint& local) const {
    if (identity_) return local;
    return {location_.apply_point(local.p), location_.apply_vector(local.su),
            location_.apply_vector(local.sv)};
  }

  const Surface& surface_;
  const Location& location_;
  bool identity_;
  Kind kind_ = Kind::Other;
  Frame frame_;
  double radius_ = 0;
};

// Panels for an interval of a parameter: trigonometric integrands need panels no wider than
// π/4 for 16-point Gauss to reach rounding; polynomial ones are exact with one panel.
int panel_count(double span, bool angular) {
  if (!angular) return 1;
  return std::max(1, static_cast<int>(std::ceil(std::abs(span) / kAngularPanel - 1e-12)));
}

// Composite Gauss–Legendre over [a, b]; f(x, node) gets the node's index as well (nodes are
// numbered panel by panel).
template <class M, class F>
M integrate_panels_indexed(const F& f, double a, double b, int panels) {
  const auto& rule = detail::gauss_legendre_rule();
  M total{};
  const double width = (b - a) / panels;
  std::size_t node = 0;
  for (int p = 0; p < panels; ++p) {
    const double lo = a + p * width;
    const double half = 0.5 * width, mid = lo + half;
    for (int k = 0; k < detail::GaussLegendreRule::kOrder; ++k) {
      const auto i = static_cast<std::size_t>(k);
      total += scaled(f(mid + half * rule.nodes[i], node++), half * rule.weights[i]);
    }
  }
  return total;
}

template <class M, class F>
M integrate_panels(const F& f, double a, double b, int panels) {
  return integrate_panels_indexed<M>([&](double x, std::size_t) { return f(x); }, a, b, panels);
}

bool same_bits(double a, double b) {
  return std::bit_cast<std::uint64_t>(a) == std::bit_cast<std::uint64_t>(b);
}

template <class M>
class FaceIntegrator {
 public:
  FaceIntegrator(const Surface& surface, const Location& location, double u_ref)
      : evaluator_(surface, location), u_ref_(u_ref) {
    angular_u_ = surface.u_period() > 0;
    angular_v_ = surface.v_period() > 0 || surface.kind() == SurfaceKind::Sphere;
    if (surface.kind() == SurfaceKind::Revolution) {
      angular_v_ = static_cast<const RevolutionSurface&>(surface).meridian()->period() > 0;
    }
  }

  // ∫ F(c(t)) v'(t) dt over [t0, t1], F(u, v) = ∫_{u_ref}^{u} f(s, v) ds: this edge use's
  // share of Green's theorem ∬ f du dv = ∮ F dv. `sampled_tolerance` > 0: the pcurve is a
  // polyline whose vertices sample a smooth curve (a traced section) within that distance
  // (world units), integrated along that curve.
  M edge_term(const Curve2d& pcurve, double t0, double t1, double sampled_tolerance = 0.0) const {
    auto g = [&](double t) {
      const Vec2 c = pcurve.point(t);
      const double dv = pcurve.derivative(t).y();
      if (dv == 0.0) return M{};
      return scaled(inner(c.x(), c.y()), dv);
    };
    switch (pcurve.kind()) {
      case Curve2dKind::Line: {
        const Vec2 d = pcurve.derivative(t0);
        if (d.y() == 0.0) return M{};  // constant v: no contribution
        const double span_u = d.x() * (t1 - t0), span_v = d.y() * (t1 - t0);
        const int panels =
            std::max(panel_count(span_u, angular_u_), panel_count(span_v, angular_v_));
        return integrate_panels<M>(g, t0, t1, panels);
      }
      case Curve2dKind::Circle:
        return integrate_panels<M>(g, t0, t1, panel_count(t1 - t0, true));
      case Curve2dKind::Trig: {
        // Trigonometric in t, plus a linear drift d·t that may sweep angular parameters.
        const Vec2 d = static_cast<const Trig2d&>(pcurve).d();
        const int drift = std::max(panel_count(d.x() * (t1 - t0), angular_u_),
                                   panel_count(d.y() * (t1 - t0), angular_v_));
        return integrate_panels<M>(g, t0, t1, std::max(panel_count(t1 - t0, true), drift));
      }
      case Curve2dKind::Polyline: {
        if (sampled_tolerance > 0.0) {
          return sampled_term(static_cast<const Polyline2d&>(pcurve), t0, t1, sampled_tolerance);
        }
        // Segments of traced sections are short (their chords are within the edge tolerance
        // of the curve): a 3-point Gauss rule per segment (exact for quintics) is far below
        // that error, and the segments are many.
        static constexpr double kNode = 0.7745966692414834;  // sqrt(3/5)
        static constexpr double kWeights[3] = {5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0};
        M total{};
        const double first = std::floor(t0), last = std::ceil(t1);
        for (double s = first; s < last; s += 1.0) {
          const double a = std::max(s, t0), b = std::min(s + 1.0, t1);
          if (b <= a) continue;
          const double half = 0.5 * (b - a), mid = a + half;
          const double nodes[3] = {-kNode, 0.0, kNode};
          for (int k = 0; k < 3; ++k) total += scaled(g(mid + half * nodes[k]), half * kWeights[k]);
        }
        return total;
      }
    }
    return M{};
  }

 private:
  // A traced section's pcurve: its vertices lie on both surfaces (Newton-refined far below
  // the tolerance), its chords up to the edge tolerance off the exact curve. Integrating the
  // chords would make the solid's volume err by about that deviation times the section's
  // length and the solid's size (the faces on either side of the section do not meet between
  // the vertices: up to 1e-2 relative for a small solid far from the origin), so the curve
  // through the vertices is integrated instead: on each segment the polynomial of degree 7
  // through the eight nearest vertices (degree 5 or 3 where fewer are evenly enough spaced),
  // parametrised by the 3D chord length, which follows arc length whatever the marching step.
  // A linear term makes it end exactly at the polyline's points at t0 and t1, where the
  // adjacent edges' pcurves end, so that the loop stays closed in (u, v). A segment keeps its
  // chord where no stencil is evenly spaced (a vertex inserted next to another one) or where
  // the interpolant strays from the chord by more than the curve can (`tolerance`, world
  // units: the chord and the image of its (u, v) chord are both within it of the curve).
  M sampled_term(const Polyline2d& pcurve, double t0, double t1, double tolerance) const {
    static constexpr double kNode = 0.7745966692414834;  // sqrt(3/5)
    static constexpr double kWeights[3] = {5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0};
    static constexpr double kSpacingRatio = 0.1;          // smallest gap / largest gap of a stencil
    static constexpr long long kStencils[3] = {8, 6, 4};  // points per stencil, tried in turn
    static constexpr long long kReach = 8;                // vertices beyond [t0, t1] used at most
    static constexpr double kStraySafety = 4.0;           // tolerances the interpolant may stray
    const std::vector<Vec2>& pts = pcurve.points();
    const auto n = static_cast<long long>(pts.size());
    if (n < 2) return M{};
    const long long first = std::clamp(static_cast<long long>(std::floor(t0)), 0LL, n - 2);
    const long long last = std::clamp(static_cast<long long>(std::ceil(t1)), first + 1, n - 1);
    // Chord lengths of the vertices the stencils may use.
    const long long k0 = std::max(0LL, first - kReach), k1 = std::min(n - 1, last + kReach);
    auto at = [&](long long k) -> const Vec2& { return pts[static_cast<std::size_t>(k)]; };
    std::vector<double> arc(static_cast<std::size_t>(k1 - k0 + 1), 0.0);
    Vec3 previous = evaluator_.evaluate(at(k0).x(), at(k0).y()).p;
    for (long long k = k0 + 1; k <= k1; ++k) {
      const Vec3 x = evaluator_.evaluate(at(k).x(), at(k).y()).p;
      arc[static_cast<std::size_t>(k - k0)] =
          arc[static_cast<std::size_t>(k - k0 - 1)] + (x - previous).norm();
      previous = x;
    }
    auto s_of = [&](long long k) { return arc[static_cast<std::size_t>(k - k0)]; };
    auto stable = [&](long long start, long long size) {
      if (start < k0 || start + size - 1 > k1) return false;
      double lo = INFINITY, hi = 0.0;
      for (long long k = start; k + 1 < start + size; ++k) {
        const double gap = s_of(k + 1) - s_of(k);
        lo = std::min(lo, gap);
        hi = std::max(hi, gap);
      }
      return hi > 0.0 && lo >= kSpacingRatio * hi;
    };
    M total{};
    for (long long seg = first; seg < last; ++seg) {
      const double a = std::max(static_cast<double>(seg), t0),
                   b = std::min(static_cast<double>(seg + 1), t1);
      if (b <= a) continue;
      // The stencil: the most central evenly spaced one of the largest size that has one.
      long long start = -1, size = 0;
      for (long long stencil : kStencils) {
        for (long long shift = 0; shift + 1 < stencil && start < 0; ++shift) {
          const long long candidate =
              seg - (stencil / 2 - 1) + (shift % 2 == 0 ? shift / 2 : -(shift + 1) / 2);
          if (stable(candidate, stencil)) start = candidate;
        }
        if (start >= 0) {
          size = stencil;
          break;
        }
      }
      const Vec2 &p0 = at(seg), &p1 = at(seg + 1);
      const double sa = s_of(seg), ds = s_of(seg + 1) - sa;
      // The interpolant (or the chord) at t, with its t-derivative.
      auto smooth = [&](double t, Vec2& d) -> Vec2 {
        const double x = t - static_cast<double>(seg);
        if (start < 0) {
          d = p1 - p0;
          return (1.0 - x) * p0 + x * p1;
        }
        const double s = sa + x * ds;
        Vec2 value = Vec2::Zero();
        d = Vec2::Zero();
        for (long long i = start; i < start + size; ++i) {
          double basis = 1.0, slope = 0.0;  // Lagrange basis of vertex i and its s-derivative
          for (long long j = start; j < start + size; ++j) {
            if (j == i) continue;
            const double w = 1.0 / (s_of(i) - s_of(j)), f = (s - s_of(j)) * w;
            slope = slope * f + basis * w;
            basis *= f;
          }
          value += basis * at(i);
          d += slope * ds * at(i);
        }
        return value;
      };
      Vec2 unused;
      if (start >= 0) {
        const Vec2 middle = smooth(seg + 0.5, unused), chord = 0.5 * (p0 + p1);
        const double stray = (evaluator_.evaluate(middle.x(), middle.y()).p -
                              evaluator_.evaluate(chord.x(), chord.y()).p)
                                 .norm();
        if (!(stray <= kStraySafety * tolerance)) start = -1;
      }
      const double xa = a - static_cast<double>(seg), xb = b - static_cast<double>(seg);
      const Vec2 ea = ((1.0 - xa) * p0 + xa * p1) - smooth(a, unused);
      const Vec2 eb = ((1.0 - xb) * p0 + xb * p1) - smooth(b, unused);
      const double half = 0.5 * (b - a), mid = a + half;
      const double nodes[3] = {-kNode, 0.0, kNode};
      for (int k = 0; k < 3; ++k) {
        const double t = mid + half * nodes[k], w = (t - a) / (b - a);
        Vec2 d;
        const Vec2 c = smooth(t, d) + (1.0 - w) * ea + w * eb;
        const double dv = d.y() + (eb.y() - ea.y()) / (b - a);
        if (dv == 0.0) continue;
        total += scaled(inner(c.x(), c.y()), dv * half * kWeights[k]);
      }
    }
    return total;
  }

  M density(double u, double v) const { return density_at(evaluator_.evaluate(u, v)); }
  M density_at(const SurfacePoint& x) const {
    const Vec3& p = x.p;
    const Vec3 n = x.su.cross(x.sv);
    if constexpr (std::is_same_v<M, VolumeMoment>) {
      return {p.dot(n) / 3.0};
    } else {
      return {n.norm(), p.dot(n) / 3.0, 0.5 * p.x() * p.x() * n.x(), 0.5 * p.y() * p.y() * n.y(),
              0.5 * p.z() * p.z() * n.z()};
    }
  }
  M inner(double u, double v) const {
    const int panels = panel_count(u - u_ref_, angular_u_);
    if constexpr (std::is_same_v<M, VolumeMoment>) {
      if (evaluator_.plane()) return {plane_inner_volume(u, v)};
      if (evaluator_.cylinder()) return {cylinder_inner_volume(u, v, panels)};
    } else {
      if (evaluator_.plane()) return plane_inner_moments(u, v);
    }
    if (!evaluator_.cylinder()) {
      auto f = [&](double s) { return density(s, v); };
      return integrate_panels<M>(f, u_ref_, u, panels);
    }
    // On a cylinder the nodes' cosines and sines depend on u only, and an edge of constant u
    // (a seam, a vertical section line) asks for one u at every outer node: the values of the
    // last u are kept (the very numbers std::cos and std::sin give, so nothing changes).
    if (trig_.empty() || !same_bits(u, trig_u_)) {
      trig_.clear();
      integrate_panels_indexed<M>(
          [&](double s, std::size_t) {
            trig_.emplace_back(std::cos(s), std::sin(s));
            return M{};
          },
          u_ref_, u, panels);
      trig_u_ = u;
    }
    auto f = [&](double, std::size_t node) {
      return density_at(evaluator_.evaluate_cylinder(trig_[node].first, trig_[node].second, v));
    };
    return integrate_panels_indexed<M>(f, u_ref_, u, panels);
  }

  // A plane p = o + s·x + v·y in world coordinates, N = x × y, and the volume integrand's
  // coefficients, found once per face.
  struct PlaneTerms {
    Vec3 o, x, y, n;
    double area = 0.0;                    // |N|
    double o3 = 0.0, x3 = 0.0, y3 = 0.0;  // o·N/3, x·N/3, y·N/3
  };
  const PlaneTerms& plane_terms() const {
    if (!plane_) {
      const SurfacePoint origin = evaluator_.evaluate(0.0, 0.0);
      const Vec3 n = origin.su.cross(origin.sv);
      plane_ = PlaneTerms{origin.p,
                          origin.su,
                          origin.sv,
                          n,
                          n.norm(),
                          origin.p.dot(n) / 3.0,
                          origin.su.dot(n) / 3.0,
                          origin.sv.dot(n) / 3.0};
    }
    return *plane_;
  }
  // The volume integrand alone (solid_volume) on a plane: linear in s, integrated in closed
  // form, (u − u_ref)·((o + v·y)·N + x·N (u + u_ref)/2) / 3. Equal to the Gauss sum of the
  // other path up to rounding.
  double plane_inner_volume(double u, double v) const {
    const PlaneTerms& p = plane_terms();
    return (u - u_ref_) * ((p.o3 + v * p.y3) + p.x3 * 0.5 * (u + u_ref_));
  }
  // All moments on a plane p = a + s·x (a = o + v·y) in closed form (each integrand is a
  // polynomial of degree at most 2 in s): area |N|·d, volume by plane_inner_volume, first
  // moments N_i/2 · d·(a_i² + a_i x_i (u + u_ref) + x_i² (u² + u·u_ref + u_ref²)/3),
  // d = u − u_ref. Equal to the Gauss sums up to rounding.
  Moments plane_inner_moments(double u, double v) const {
    const PlaneTerms& p = plane_terms();
    const double r = u_ref_, d = u - r, sum = u + r, squares = (u * u + u * r + r * r) / 3.0;
    const Vec3 a = p.o + v * p.y;
    Moments m;
    m[0] = p.area * d;
    m[1] = plane_inner_volume(u, v);  // the very numbers solid_volume sums
    for (int i = 0; i < 3; ++i) {
      m[static_cast<std::size_t>(2 + i)] =
          0.5 * p.n[i] * d * (a[i] * a[i] + a[i] * p.x[i] * sum + p.x[i] * p.x[i] * squares);
    }
    return m;
  }
  // On a cylinder p = P(s) + v·z with N(s) = S_u(s) × z: p·N = P·N + v z·N (z·N vanishes up to
  // rounding), so the u-integral is A(u) + v·B(u), and both are kept for the last u (an edge of
  // constant u, a seam or a vertical section line, asks for one u at every outer node).
  double cylinder_inner_volume(double u, double v, int panels) const {
    if (!cylinder_ready_ || !same_bits(u, cylinder_u_)) {
      const auto f = [&](double s, std::size_t) {
        const SurfacePoint x = evaluator_.evaluate_cylinder(std::cos(s), std::sin(s), 0.0);
        const Vec3 n = x.su.cross(x.sv);
        return std::array<double, 2>{x.p.dot(n) / 3.0, x.sv.dot(n) / 3.0};
      };
      cylinder_ab_ = integrate_panels_indexed<std::array<double, 2>>(f, u_ref_, u, panels);
      cylinder_u_ = u;
      cylinder_ready_ = true;
    }
    return cylinder_ab_[0] + v * cylinder_ab_[1];
  }

  SurfaceEvaluator evaluator_;
  double u_ref_;
  mutable double trig_u_ = 0;  // inner()'s cache: the u of trig_
  mutable std::vector<std::pair<double, double>> trig_;
  mutable std::optional<PlaneTerms> plane_;  // plane_terms()
  mutable bool cylinder_ready_ = false;      // cylinder_inner_volume's cache
  mutable double cylinder_u_ = 0;
  mutable std::array<double, 2> cylinder_ab_{};
  bool angular_u_ = false, angular_v_ = false;
};

template <class M>
M face_moments(const Shape& face) {
  const ShapeBody& body = face.body();
  const FaceData& data = *body.face();
  // Integrate over the face body (its own wires and edge orientations: the outer loop is
  // counter-clockwise in (u, v)), then apply the face's orientation to the flux terms. The
  // walk is over bodies (no Shape made per wire and edge use).
  const auto& wires = body.children();
  if (wires.empty()) return M{};
  double u_ref = 0.0;
  if (!wires[0].body().children().empty()) {
    u_ref = data.pcurves[0][0]->point(wires[0].body().children()[0].body().edge()->first).x();
  }
  FaceIntegrator<M> integrator(*data.surface, face.location(), u_ref);
  M total{};
  for (std::size_t w = 0; w < wires.size(); ++w) {
    const Orientation wo = wires[w].orientation();
    const auto& edges = wires[w].body().children();
    for (std::size_t e = 0; e < edges.size(); ++e) {
      const Orientation o = compose(wo, edges[e].orientation());
      if (o != Orientation::Forward && o != Orientation::Reversed) continue;
      const EdgeData& ed = *edges[e].body().edge();
      // A polyline with a tolerance samples a smooth curve (a traced section); one without is
      // exact (a polygon).
      double sampled_tolerance = 0.0;
      if (ed.curve && ed.curve->kind() == CurveKind::Polyline) {
        sampled_tolerance =
            static_cast<const PolylineCurve&>(*ed.curve).tolerance() * face.location().scale();
      }
      M m = integrator.edge_term(*data.pcurves[w][e], ed.first, ed.last, sampled_tolerance);
      total += scaled(m, o == Orientation::Forward ? 1.0 : -1.0);
    }
  }
  const Orientation fo = face.orientation();
  const double flux_sign = fo == Orientation::Forward    ? 1.0
                           : fo == Orientation::Reversed ? -1.0
                                                         : 0.0;
  M out = scaled(total, flux_sign);
  if constexpr (!std::is_same_v<M, VolumeMoment>) out[0] = std::abs(total[0]);
  return out;
}

}  // namespace

namespace {

// The bounds below walk bodies with the location accumulated down to them, not Shapes: a
// box's vertex is met six times and an edge twice, and each Shape made on the way would
// count references to its body and location up and down again.

void add_edge_bounds(BoundingBox& box, const EdgeData& d, const Location& loc) {
  if (d.degenerate()) return;
  // The edge's range on the moved curve (a line's arc length scales with the location).
  const double k = detail::moved_parameter_scale(*d.curve, loc);
  if (d.curve->kind() == CurveKind::Line) {
    // The moved line as transformed() makes it, on the stack (boxes of many edges).
    const auto& line = static_cast<const LineCurve&>(*d.curve);
    const LineCurve moved(loc.apply_point(line.origin()), loc.apply_direction(line.direction()));
    box.add(moved.bounds(d.first * k, d.last * k));
    return;
  }
  box.add(d.curve->transformed(loc)->bounds(d.first * k, d.last * k));
}

// A plane's extremes lie on its boundary; a curved face can bulge between its edges, so the
// patch over the (u, v) box of its boundary is added.
void add_face_patch(BoundingBox& box, const ShapeBody& face, const Location& loc) {
  const FaceData& d = *face.face();
  if (d.surface->kind() == SurfaceKind::Plane) return;
  ParamBox pb{INFINITY, -INFINITY, INFINITY, -INFINITY};
  for (std::size_t w = 0; w < face.children().size(); ++w) {
    const auto& edges = face.children()[w].body().children();
    for (std::size_t e = 0; e < edges.size(); ++e) {
      const EdgeData& ed = *edges[e].body().edge();
      const Curve2d& pc = *d.pcurves[w][e];
      const int samples = pc.kind() == Curve2dKind::Line ? 1 : 64;
      for (int k = 0; k <= samples; ++k) {
        const Vec2 p = pc.point(ed.first + (ed.last - ed.first) * k / samples);
        pb.u0 = std::min(pb.u0, p.x());
        pb.u1 = std::max(pb.u1, p.x());
        pb.v0 = std::min(pb.v0, p.y());
        pb.v1 = std::max(pb.v1, p.y());
      }
    }
  }
  if (pb.u0 <= pb.u1) {
    // The moved surface measures its length parameters in world units (scaled by the
    // location); angles are unchanged.
    const double s = loc.scale();
    const SurfaceKind k = d.surface->kind();
    if (k == SurfaceKind::Cylinder || k == SurfaceKind::Cone || k == SurfaceKind::Extrusion) {
      pb.v0 *= s;
      pb.v1 *= s;
    }
    box.add(d.surface->transformed(loc)->bounds(pb));
  }
}

// Every vertex and edge under the body placed at `loc` (wires, edges, vertices, in any
// orientation: bounds do not depend on it), walked without the index of distinct
// sub-shapes; with `patches`, every face's patch too.
void add_descendants(BoundingBox& box, const ShapeBody& body, const Location& loc, bool patches) {
  for (const Shape& child : body.children()) {
    // Children at the identity (almost all) keep the parent's location as it is, uncopied.
    Location composed;
    const Location& moved =
        child.location().is_identity() ? loc : (composed = loc * child.location());
    const ShapeBody& b = child.body();
    if (const VertexData* v = b.vertex()) {
      box.add(moved.apply_point(v->point));
      continue;
    }
    if (const EdgeData* e = b.edge()) add_edge_bounds(box, *e, moved);
    if (patches && b.kind() == ShapeKind::Face) add_face_patch(box, b, moved);
    add_descendants(box, b, moved, patches);
  }
}

}  // namespace

BoundingBox bounding_box(const Shape& shape) {
  BoundingBox box;
  if (shape.is_null()) return box;
  const ShapeBody& body = shape.body();
  const Location& loc = shape.location();
  if (shape.kind() == ShapeKind::Face) {
    // One face (the Booleans take every face's box): walked directly, without the index of
    // distinct edges (a box is a union: an edge seen twice, a seam, adds nothing).
    add_descendants(box, body, loc, false);
    add_face_patch(box, body, loc);
    return box;
  }
  // Walked directly too: an edge or a face met again (its other face, a shared face) adds
  // nothing to a union, and walking it twice costs less than the index of distinct ones.
  if (shape.kind() == ShapeKind::Vertex) {
    box.add(vertex_point(shape));
    return box;
  }
  if (shape.kind() == ShapeKind::Edge) add_edge_bounds(box, *body.edge(), loc);
  add_descendants(box, body, loc, true);
  return box;
}

namespace {

// Area, volume and first moments summed over the faces (zeros for a null shape).
Moments moments_of(const Shape& shape) {
  Moments total{};
  if (shape.is_null()) return total;
  for (const Shape& face : Explorer(shape, ShapeKind::Face)) total += face_moments<Moments>(face);
  return total;
}

}  // namespace

double shape_volume(const Shape& shape) { return moments_of(shape)[1]; }

MassProperties mass_properties(const Shape& shape) {
  MassProperties mp;
  if (shape.is_null()) return mp;
  const Moments total = moments_of(shape);
  mp.area = total[0];
  mp.volume = total[1];
  if (mp.volume != 0.0) {
    mp.centroid = Vec3(total[2], total[3], total[4]) / mp.volume;
  }
  mp.bounds = bounding_box(shape);
  if (mp.volume == 0.0 && !mp.bounds.empty()) mp.centroid = 0.5 * (mp.bounds.min + mp.bounds.max);
  return mp;
}

namespace detail {

double solid_volume(const Shape& shape) {
  if (shape.is_null()) return 0.0;
  VolumeMoment total{};
  for (const Shape& face : Explorer(shape, ShapeKind::Face))
    total += face_moments<VolumeMoment>(face);
  return total[0];
}

}  // namespace detail

}  // namespace csgtile::kernel
