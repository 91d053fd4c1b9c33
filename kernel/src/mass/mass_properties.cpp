#include "csgtile/kernel/mass_properties.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

#include "csgtile/kernel/explorer.h"
#include "geometry/geometry_internal.h"

namespace csgtile::kernel {

namespace {

// Integrands per unit (u, v) area, N = S_u × S_v in world coordinates (un-normalised).
// 0: area |N|, 1: volume p·N / 3, 2..4: first moments p_i² N_i / 2.
using Moments = std::array<double, 5>;

constexpr double kAngularPanel = std::numbers::pi / 4;

Moments& operator+=(Moments& a, const Moments& b) {
  for (std::size_t i = 0; i < a.size(); ++i) a[i] += b[i];
  return a;
}
Moments scaled(const Moments& m, double s) {
  Moments out;
  for (std::size_t i = 0; i < m.size(); ++i) out[i] = m[i] * s;
  return out;
}

// Panels for an interval of a parameter: trigonometric integrands need panels no wider than
// π/4 for 16-point Gauss to reach rounding; polynomial ones are exact with one panel.
int panel_count(double span, bool angular) {
  if (!angular) return 1;
  return std::max(1, static_cast<int>(std::ceil(std::abs(span) / kAngularPanel - 1e-12)));
}

template <class F>
Moments integrate_panels(const F& f, double a, double b, int panels) {
  const auto& rule = detail::gauss_legendre_rule();
  Moments total{};
  const double width = (b - a) / panels;
  for (int p = 0; p < panels; ++p) {
    const double lo = a + p * width;
    const double half = 0.5 * width, mid = lo + half;
    for (int k = 0; k < detail::GaussLegendreRule::kOrder; ++k) {
      const auto i = static_cast<std::size_t>(k);
      total += scaled(f(mid + half * rule.nodes[i]), half * rule.weights[i]);
    }
  }
  return total;
}

class FaceIntegrator {
 public:
  FaceIntegrator(const Surface& surface, const Location& location, double u_ref)
      : surface_(surface), location_(location), u_ref_(u_ref) {
    angular_u_ = surface.u_period() > 0;
    angular_v_ = surface.v_period() > 0 || surface.kind() == SurfaceKind::Sphere;
    if (surface.kind() == SurfaceKind::Revolution) {
      angular_v_ = static_cast<const RevolutionSurface&>(surface).meridian()->period() > 0;
    }
  }

  // ∫ F(c(t)) v'(t) dt over [t0, t1], F(u, v) = ∫_{u_ref}^{u} f(s, v) ds: this edge use's
  // share of Green's theorem ∬ f du dv = ∮ F dv.
  Moments edge_term(const Curve2d& pcurve, double t0, double t1) const {
    auto g = [&](double t) {
      const Vec2 c = pcurve.point(t);
      const double dv = pcurve.derivative(t).y();
      if (dv == 0.0) return Moments{};
      return scaled(inner(c.x(), c.y()), dv);
    };
    switch (pcurve.kind()) {
      case Curve2dKind::Line: {
        const Vec2 d = pcurve.derivative(t0);
        if (d.y() == 0.0) return Moments{};  // constant v: no contribution
        const double span_u = d.x() * (t1 - t0), span_v = d.y() * (t1 - t0);
        const int panels = std::max(panel_count(span_u, angular_u_), panel_count(span_v, angular_v_));
        return integrate_panels(g, t0, t1, panels);
      }
      case Curve2dKind::Circle:
        return integrate_panels(g, t0, t1, panel_count(t1 - t0, true));
      case Curve2dKind::Trig: {
        // Trigonometric in t, plus a linear drift d·t that may sweep angular parameters.
        const Vec2 d = static_cast<const Trig2d&>(pcurve).d();
        const int drift = std::max(panel_count(d.x() * (t1 - t0), angular_u_),
                                   panel_count(d.y() * (t1 - t0), angular_v_));
        return integrate_panels(g, t0, t1, std::max(panel_count(t1 - t0, true), drift));
      }
      case Curve2dKind::Polyline: {
        // Segments of traced sections are short (their chords are within the edge tolerance
        // of the curve): a 3-point Gauss rule per segment (exact for quintics) is far below
        // that error, and the segments are many.
        static constexpr double kNode = 0.7745966692414834;  // sqrt(3/5)
        static constexpr double kWeights[3] = {5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0};
        Moments total{};
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
    return Moments{};
  }

 private:
  Moments density(double u, double v) const {
    const Vec3 p = location_.apply_point(surface_.point(u, v));
    const Vec3 n = location_.apply_vector(surface_.du(u, v)).cross(location_.apply_vector(surface_.dv(u, v)));
    return {n.norm(), p.dot(n) / 3.0, 0.5 * p.x() * p.x() * n.x(), 0.5 * p.y() * p.y() * n.y(),
            0.5 * p.z() * p.z() * n.z()};
  }
  Moments inner(double u, double v) const {
    auto f = [&](double s) { return density(s, v); };
    return integrate_panels(f, u_ref_, u, panel_count(u - u_ref_, angular_u_));
  }

  const Surface& surface_;
  const Location& location_;
  double u_ref_;
  bool angular_u_ = false, angular_v_ = false;
};

Moments face_moments(const Shape& face) {
  const FaceData& data = *face.body().face();
  // Integrate over the face body (its own wires and edge orientations: the outer loop is
  // counter-clockwise in (u, v)), then apply the face's orientation to the flux terms.
  const Shape body_face = face.oriented(Orientation::Forward);
  if (body_face.child_count() == 0) return Moments{};
  double u_ref = 0.0;
  {
    const Shape wire = body_face.child(0);
    if (wire.child_count() > 0) {
      const Shape edge = wire.child(0);
      u_ref = data.pcurves[0][0]->point(edge.body().edge()->first).x();
    }
  }
  FaceIntegrator integrator(*data.surface, face.location(), u_ref);
  Moments total{};
  for (std::size_t w = 0; w < body_face.child_count(); ++w) {
    const Shape wire = body_face.child(w);
    for (std::size_t e = 0; e < wire.child_count(); ++e) {
      const Shape edge = wire.child(e);
      const Orientation o = edge.orientation();
      if (o != Orientation::Forward && o != Orientation::Reversed) continue;
      const EdgeData& ed = *edge.body().edge();
      Moments m = integrator.edge_term(*data.pcurves[w][e], ed.first, ed.last);
      total += scaled(m, o == Orientation::Forward ? 1.0 : -1.0);
    }
  }
  const Orientation fo = face.orientation();
  const double flux_sign = fo == Orientation::Forward ? 1.0 : fo == Orientation::Reversed ? -1.0 : 0.0;
  Moments out = scaled(total, flux_sign);
  out[0] = std::abs(total[0]);
  return out;
}

}  // namespace

BoundingBox bounding_box(const Shape& shape) {
  BoundingBox box;
  if (shape.is_null()) return box;
  for (const Shape& v : Explorer(shape, ShapeKind::Vertex)) box.add(vertex_point(v));
  const ShapeIndex edges = map_child_shapes(shape, ShapeKind::Edge);
  for (const Shape& e : edges.shapes()) {
    const EdgeData& d = *e.body().edge();
    if (d.degenerate()) continue;
    box.add(d.curve->transformed(e.location())->bounds(d.first, d.last));
  }
  // A plane's extremes lie on its boundary; curved faces can bulge between their edges, so
  // add the patch over the (u, v) box of their boundary.
  const ShapeIndex faces = map_child_shapes(shape, ShapeKind::Face);
  for (const Shape& f : faces.shapes()) {
    const FaceData& d = *f.body().face();
    if (d.surface->kind() == SurfaceKind::Plane) continue;
    ParamBox pb{INFINITY, -INFINITY, INFINITY, -INFINITY};
    const Shape body_face = f.oriented(Orientation::Forward);
    for (std::size_t w = 0; w < body_face.child_count(); ++w) {
      const Shape wire = body_face.child(w);
      for (std::size_t e = 0; e < wire.child_count(); ++e) {
        const EdgeData& ed = *wire.child(e).body().edge();
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
      const double s = f.location().scale();
      const SurfaceKind k = d.surface->kind();
      if (k == SurfaceKind::Cylinder || k == SurfaceKind::Cone || k == SurfaceKind::Extrusion) {
        pb.v0 *= s;
        pb.v1 *= s;
      }
      box.add(d.surface->transformed(f.location())->bounds(pb));
    }
  }
  return box;
}

MassProperties mass_properties(const Shape& shape) {
  MassProperties mp;
  if (shape.is_null()) return mp;
  Moments total{};
  for (const Shape& face : Explorer(shape, ShapeKind::Face)) total += face_moments(face);
  mp.area = total[0];
  mp.volume = total[1];
  if (mp.volume != 0.0) {
    mp.centroid = Vec3(total[2], total[3], total[4]) / mp.volume;
  }
  mp.bounds = bounding_box(shape);
  if (mp.volume == 0.0 && !mp.bounds.empty()) mp.centroid = 0.5 * (mp.bounds.min + mp.bounds.max);
  return mp;
}

}  // namespace csgtile::kernel
