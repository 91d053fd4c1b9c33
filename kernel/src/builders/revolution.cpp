// Solids of revolution about Z: revolved polygon profiles (cylinder, cone and frustum are
// special cases), sphere and torus.
//
// A profile segment P_a -> P_b revolved over u in [0, A] is a face whose boundary, in the
// logical rectangle (u, w) with w running along the segment, is: the arc of P_a, the
// segment placed at u = A, the arc of P_b, the segment placed at u = 0. Arcs collapse on
// the axis (a degenerate edge on cones, nothing on planes); for a full turn the two placed
// segments are one seam edge, and planar faces drop it (they are bounded by circles).

#include <cmath>
#include <map>
#include <numbers>
#include <optional>
#include <string>

#include "csgtile/kernel/polygon2d.h"
#include "csgtile/kernel/primitives.h"

namespace csgtile::kernel {

namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

Vec3 radial(double u) { return Vec3(std::cos(u), std::sin(u), 0.0); }

struct EdgeUse {
  Shape edge;
  Curve2dPtr pcurve;
};

class RevolutionBuilder {
 public:
  RevolutionBuilder(std::vector<Vec2> profile, double angle, double tolerance)
      : profile_(std::move(profile)), angle_(angle), tol_(tolerance), full_(angle >= kTwoPi) {}

  Result<Shape> build() {
    const std::size_t n = profile_.size();
    std::vector<Shape> faces;
    for (std::size_t s = 0; s < n; ++s) {
      const Vec2 a = profile_[s], b = profile_[(s + 1) % n];
      if (a.x() == 0.0 && b.x() == 0.0) continue;  // on the axis: bounds no revolved face
      auto face = revolved_face(s, a, b);
      if (!face.ok()) return face;
      faces.push_back(std::move(face).value());
    }
    if (!full_) {
      for (double u : {0.0, angle_}) {
        auto cap = cap_face(u);
        if (!cap.ok()) return cap;
        faces.push_back(std::move(cap).value());
      }
    }
    auto shell = ShapeFactory::shell(std::move(faces));
    if (!shell.ok()) return shell;
    return ShapeFactory::solid({std::move(shell).value()});
  }

 private:
  // Vertex of profile point i placed at angle u (one vertex per axis point; a full turn
  // has one vertex per off-axis point, at u = 0).
  Result<Shape> vertex(std::size_t i, double u) {
    const Vec2 p = profile_[i];
    const bool on_axis = p.x() == 0.0;
    const int slot = (on_axis || full_ || u == 0.0) ? 0 : 1;
    const auto key = std::make_pair(i, slot);
    if (auto it = vertices_.find(key); it != vertices_.end()) return it->second;
    auto v = ShapeFactory::vertex(p.x() * radial(slot == 0 ? 0.0 : angle_) + p.y() * Vec3::UnitZ(),
                                  tol_);
    if (!v.ok()) return v;
    vertices_.emplace(key, v.value());
    return v;
  }

  // Arc (full circle for a full turn) of off-axis profile point i, parameter = angle.
  Result<Shape> arc(std::size_t i) {
    if (auto it = arcs_.find(i); it != arcs_.end()) return it->second;
    const Vec2 p = profile_[i];
    auto start = vertex(i, 0.0);
    auto end = vertex(i, full_ ? 0.0 : angle_);
    if (!start.ok()) return start;
    if (!end.ok()) return end;
    Frame frame;
    frame.origin = Vec3(0, 0, p.y());
    auto e = ShapeFactory::edge(std::make_shared<CircleCurve>(frame, p.x()), 0.0,
                                full_ ? kTwoPi : angle_, start.value(), end.value(), tol_);
    if (!e.ok()) return e;
    arcs_.emplace(i, e.value());
    return e;
  }

  // Profile segment s (from point s to s+1) placed at angle u, parametrised by arc length
  // from P_s. The two caps of a partial turn share the segments lying on the axis.
  Result<Shape> segment(std::size_t s, double u) {
    const std::size_t n = profile_.size();
    const Vec2 a = profile_[s], b = profile_[(s + 1) % n];
    const bool on_axis = a.x() == 0.0 && b.x() == 0.0;
    const int slot = (on_axis || full_ || u == 0.0) ? 0 : 1;
    const auto key = std::make_pair(s, slot);
    if (auto it = segments_.find(key); it != segments_.end()) return it->second;
    auto va = vertex(s, u);
    auto vb = vertex((s + 1) % n, u);
    if (!va.ok()) return va;
    if (!vb.ok()) return vb;
    const Vec3 pa = vertex_point(va.value()), pb = vertex_point(vb.value());
    auto e = ShapeFactory::edge(std::make_shared<LineCurve>(pa, pb - pa), 0.0, (pb - pa).norm(),
                                va.value(), vb.value(), tol_);
    if (!e.ok()) return e;
    segments_.emplace(key, e.value());
    return e;
  }

  Result<Shape> degenerate(std::size_t i) {
    if (auto it = degenerates_.find(i); it != degenerates_.end()) return it->second;
    auto v = vertex(i, 0.0);
    if (!v.ok()) return v;
    auto e = ShapeFactory::degenerate_edge(v.value(), 0.0, angle_, tol_);
    if (!e.ok()) return e;
    degenerates_.emplace(i, e.value());
    return e;
  }

  Result<Shape> revolved_face(std::size_t s, const Vec2& a, const Vec2& b) {
    const std::size_t n = profile_.size();
    const std::size_t ia = s, ib = (s + 1) % n;
    const double dr = b.x() - a.x(), dz = b.y() - a.y();
    const double length = std::hypot(dr, dz);
    // Outward normal of the segment in the (rho, z) plane: the profile is counter-clockwise,
    // so the material is on the left and the outside on the right.
    const Vec2 outward(dz, -dr);

    SurfacePtr surface;
    bool planar = false;
    // w(t): the logical coordinate along the segment at arc length t from P_a, as an affine
    // map w = w_a + w_rate * t; for curved faces w is the surface's v parameter.
    double w_a = 0.0, w_rate = 1.0;
    Orientation orientation = Orientation::Forward;
    if (dz == 0.0) {
      planar = true;
      Frame frame;
      frame.origin = Vec3(0, 0, a.y());
      surface = std::make_shared<PlaneSurface>(frame);
      w_a = a.x();
      w_rate = dr / length;
      orientation = outward.y() > 0 ? Orientation::Forward : Orientation::Reversed;
    } else if (dr == 0.0) {
      surface = std::make_shared<CylinderSurface>(Frame(), a.x());
      w_a = a.y();
      w_rate = dz / length;
      orientation = dz > 0 ? Orientation::Forward : Orientation::Reversed;
    } else {
      // v runs up the generatrix (cos φ > 0); reference circle at P_a.
      const double up = dz > 0 ? 1.0 : -1.0;
      const double semi_angle = std::atan2(up * dr, up * dz);
      Frame frame;
      frame.origin = Vec3(0, 0, a.y());
      surface = std::make_shared<ConeSurface>(frame, a.x(), semi_angle);
      w_a = 0.0;
      w_rate = up;
      orientation = dz > 0 ? Orientation::Forward : Orientation::Reversed;
    }
    const double w_b = w_a + w_rate * length;

    // Loop counter-clockwise in the logical (u, w) rectangle.
    std::vector<EdgeUse> loop;
    auto side_arc = [&](std::size_t i, double w, bool forward) -> Status {
      if (profile_[i].x() == 0.0) {
        if (planar) return {};
        auto e = degenerate(i);
        if (!e.ok()) return e.error();
        loop.push_back({forward ? e.value() : e.value().reversed(),
                        std::make_shared<Line2d>(Vec2(0.0, w), Vec2(1.0, 0.0))});
        return {};
      }
      auto e = arc(i);
      if (!e.ok()) return e.error();
      Curve2dPtr pc = planar ? Curve2dPtr(std::make_shared<Circle2d>(Vec2::Zero(), profile_[i].x()))
                             : Curve2dPtr(std::make_shared<Line2d>(Vec2(0.0, w), Vec2(1.0, 0.0)));
      loop.push_back({forward ? e.value() : e.value().reversed(), pc});
      return {};
    };
    auto side_segment = [&](double u, bool forward) -> Status {
      auto e = segment(s, u);
      if (!e.ok()) return e.error();
      Curve2dPtr pc;
      if (planar) {
        const Vec2 dir(std::cos(u), std::sin(u));
        pc = std::make_shared<Line2d>(a.x() * dir, (dr / length) * dir);
      } else {
        pc = std::make_shared<Line2d>(Vec2(u, w_a), Vec2(0.0, w_rate));
      }
      loop.push_back({forward ? e.value() : e.value().reversed(), pc});
      return {};
    };

    const bool w_increases = w_b > w_a;
    const std::size_t low = w_increases ? ia : ib, high = w_increases ? ib : ia;
    const double w_low = std::min(w_a, w_b), w_high = std::max(w_a, w_b);
    std::vector<std::vector<EdgeUse>> wires;
    if (planar && full_) {
      // Annulus or disc: outer circle counter-clockwise around +Z, inner one clockwise.
      for (std::size_t i : {high, low}) {
        if (profile_[i].x() == 0.0) continue;
        auto e = arc(i);
        if (!e.ok()) return e.error();
        const bool outer = i == high;
        wires.push_back({{outer ? e.value() : e.value().reversed(),
                          std::make_shared<Circle2d>(Vec2::Zero(), profile_[i].x())}});
      }
    } else {
      if (auto st = side_arc(low, w_low, true); !st.ok()) return st.error();
      if (auto st = side_segment(full_ ? kTwoPi : angle_, w_increases); !st.ok()) return st.error();
      if (auto st = side_arc(high, w_high, false); !st.ok()) return st.error();
      if (auto st = side_segment(0.0, !w_increases); !st.ok()) return st.error();
      if (planar) {
        // (u, rho) -> (x, y) reverses orientation: walk the loop backwards so that it is
        // counter-clockwise around the plane's normal.
        std::reverse(loop.begin(), loop.end());
        for (EdgeUse& use : loop) use.edge = use.edge.reversed();
      }
      wires.push_back(std::move(loop));
    }

    std::vector<Shape> wire_shapes;
    std::vector<std::vector<Curve2dPtr>> pcurves;
    for (auto& uses : wires) {
      std::vector<Shape> edges;
      std::vector<Curve2dPtr> curves;
      for (auto& use : uses) {
        edges.push_back(use.edge);
        curves.push_back(use.pcurve);
      }
      auto wire = ShapeFactory::wire(std::move(edges));
      if (!wire.ok()) return wire;
      wire_shapes.push_back(std::move(wire).value());
      pcurves.push_back(std::move(curves));
    }
    auto face = ShapeFactory::face(surface, std::move(wire_shapes), std::move(pcurves), tol_);
    if (!face.ok()) return face;
    return face.value().oriented(orientation);
  }

  // End face of a partial turn: the profile polygon in the half-plane at angle u. Its plane
  // has x = radial(u), y = Z, so (u, v) = (rho, z) and the counter-clockwise profile is
  // counter-clockwise around the plane normal radial(u) × Z = -tangent(u): outward at u = 0,
  // inward at u = A.
  Result<Shape> cap_face(double u) {
    Frame frame;
    frame.x = radial(u);
    frame.y = Vec3::UnitZ();
    frame.z = frame.x.cross(frame.y);
    auto surface = std::make_shared<PlaneSurface>(frame);
    std::vector<Shape> edges;
    std::vector<Curve2dPtr> curves;
    const std::size_t n = profile_.size();
    for (std::size_t s = 0; s < n; ++s) {
      auto e = segment(s, u);
      if (!e.ok()) return e;
      const Vec2 a = profile_[s], b = profile_[(s + 1) % n];
      edges.push_back(e.value());
      curves.push_back(std::make_shared<Line2d>(a, (b - a) / (b - a).norm()));
    }
    auto wire = ShapeFactory::wire(std::move(edges));
    if (!wire.ok()) return wire;
    auto face = ShapeFactory::face(surface, {wire.value()}, {curves}, tol_);
    if (!face.ok()) return face;
    return face.value().oriented(u == 0.0 ? Orientation::Forward : Orientation::Reversed);
  }

  std::vector<Vec2> profile_;
  double angle_;
  double tol_;
  bool full_;
  std::map<std::pair<std::size_t, int>, Shape> vertices_;
  std::map<std::size_t, Shape> arcs_;
  std::map<std::pair<std::size_t, int>, Shape> segments_;
  std::map<std::size_t, Shape> degenerates_;
};

}  // namespace

Result<Shape> make_revolution(const std::vector<Vec2>& profile, double angle, double tolerance) {
  if (!(angle > 0.0) || angle > kTwoPi + 1e-12 || !std::isfinite(angle)) {
    return Error{ErrorCode::InvalidArgument, "revolution angle must be in (0, 2*pi]"};
  }
  std::vector<Vec2> ring;
  for (Vec2 p : profile) {
    if (!p.allFinite()) return Error{ErrorCode::InvalidArgument, "profile has a non-finite point"};
    if (p.x() < -tolerance) {
      return Error{ErrorCode::DegenerateGeometry, "profile crosses the axis (rho < 0)"};
    }
    if (p.x() <= tolerance) p.x() = 0.0;  // on the axis, exactly
    ring.push_back(p);
  }
  ring = clean_ring(ring, tolerance);
  if (ring.size() < 3 || std::abs(ring_area(ring)) <= 0.5 * tolerance * tolerance) {
    return Error{ErrorCode::DegenerateGeometry, "revolution profile has no area"};
  }
  if (ring_self_intersects(ring)) {
    return Error{ErrorCode::DegenerateGeometry, "revolution profile intersects itself"};
  }
  if (ring_area(ring) < 0) std::reverse(ring.begin(), ring.end());
  return RevolutionBuilder(std::move(ring), std::min(angle, kTwoPi), tolerance).build();
}

Result<Shape> make_cylinder(double r, double h, double tolerance) {
  if (!(r > 0) || !(h > 0) || !std::isfinite(r) || !std::isfinite(h)) {
    return Error{ErrorCode::InvalidArgument, "cylinder needs r > 0 and h > 0"};
  }
  return make_revolution({{0, 0}, {r, 0}, {r, h}, {0, h}}, kTwoPi, tolerance);
}

Result<Shape> make_cone(double r1, double r2, double h, double tolerance) {
  if (!(r1 >= 0) || !(r2 >= 0) || !(h > 0) || !std::isfinite(r1) || !std::isfinite(r2) ||
      !std::isfinite(h) || (r1 == 0 && r2 == 0)) {
    return Error{ErrorCode::InvalidArgument, "cone needs r1, r2 >= 0 (not both 0) and h > 0"};
  }
  std::vector<Vec2> profile{{0, 0}};
  if (r1 > 0) profile.emplace_back(r1, 0);
  if (r2 > 0) profile.emplace_back(r2, h);
  profile.emplace_back(0, h);
  return make_revolution(profile, kTwoPi, tolerance);
}

Result<Shape> make_sphere(double r, double tolerance) {
  if (!(r > 0) || !std::isfinite(r)) return Error{ErrorCode::InvalidArgument, "sphere needs r > 0"};
  constexpr double kHalfPi = std::numbers::pi / 2;
  auto south = ShapeFactory::vertex(Vec3(0, 0, -r), tolerance);
  auto north = ShapeFactory::vertex(Vec3(0, 0, r), tolerance);
  if (!south.ok()) return south;
  if (!north.ok()) return north;
  // Seam: the meridian u = 0, C(t) = r·cos t·X + r·sin t·Z = S(0, t).
  Frame meridian;
  meridian.x = Vec3::UnitX();
  meridian.y = Vec3::UnitZ();
  meridian.z = meridian.x.cross(meridian.y);
  auto seam = ShapeFactory::edge(std::make_shared<CircleCurve>(meridian, r), -kHalfPi, kHalfPi,
                                 south.value(), north.value(), tolerance);
  auto south_pole = ShapeFactory::degenerate_edge(south.value(), 0.0, kTwoPi, tolerance);
  auto north_pole = ShapeFactory::degenerate_edge(north.value(), 0.0, kTwoPi, tolerance);
  if (!seam.ok()) return seam;
  if (!south_pole.ok()) return south_pole;
  if (!north_pole.ok()) return north_pole;
  // Counter-clockwise around [0, 2π] × [-π/2, π/2].
  auto wire = ShapeFactory::wire(
      {south_pole.value(), seam.value(), north_pole.value().reversed(), seam.value().reversed()});
  if (!wire.ok()) return wire;
  std::vector<Curve2dPtr> pcurves{std::make_shared<Line2d>(Vec2(0, -kHalfPi), Vec2(1, 0)),
                                  std::make_shared<Line2d>(Vec2(kTwoPi, 0), Vec2(0, 1)),
                                  std::make_shared<Line2d>(Vec2(0, kHalfPi), Vec2(1, 0)),
                                  std::make_shared<Line2d>(Vec2(0, 0), Vec2(0, 1))};
  auto face = ShapeFactory::face(std::make_shared<SphereSurface>(Frame(), r), {wire.value()},
                                 {pcurves}, tolerance);
  if (!face.ok()) return face;
  auto shell = ShapeFactory::shell({face.value()});
  if (!shell.ok()) return shell;
  return ShapeFactory::solid({shell.value()});
}

Result<Shape> make_torus(double major_radius, double minor_radius, double tolerance) {
  if (!(minor_radius > 0) || !(major_radius > minor_radius) || !std::isfinite(major_radius)) {
    return Error{ErrorCode::InvalidArgument, "torus needs R > r > 0"};
  }
  const double big = major_radius, small = minor_radius;
  auto v = ShapeFactory::vertex(Vec3(big + small, 0, 0), tolerance);
  if (!v.ok()) return v;
  // Equator seam v = 0: C(t) = S(t, 0); meridian seam u = 0: C(t) = S(0, t).
  Frame meridian;
  meridian.origin = Vec3(big, 0, 0);
  meridian.x = Vec3::UnitX();
  meridian.y = Vec3::UnitZ();
  meridian.z = meridian.x.cross(meridian.y);
  auto equator = ShapeFactory::edge(std::make_shared<CircleCurve>(Frame(), big + small), 0.0,
                                    kTwoPi, v.value(), v.value(), tolerance);
  auto meridian_edge = ShapeFactory::edge(std::make_shared<CircleCurve>(meridian, small), 0.0,
                                          kTwoPi, v.value(), v.value(), tolerance);
  if (!equator.ok()) return equator;
  if (!meridian_edge.ok()) return meridian_edge;
  auto wire = ShapeFactory::wire({equator.value(), meridian_edge.value(),
                                  equator.value().reversed(), meridian_edge.value().reversed()});
  if (!wire.ok()) return wire;
  std::vector<Curve2dPtr> pcurves{std::make_shared<Line2d>(Vec2(0, 0), Vec2(1, 0)),
                                  std::make_shared<Line2d>(Vec2(kTwoPi, 0), Vec2(0, 1)),
                                  std::make_shared<Line2d>(Vec2(0, kTwoPi), Vec2(1, 0)),
                                  std::make_shared<Line2d>(Vec2(0, 0), Vec2(0, 1))};
  auto face = ShapeFactory::face(std::make_shared<TorusSurface>(Frame(), big, small),
                                 {wire.value()}, {pcurves}, tolerance);
  if (!face.ok()) return face;
  auto shell = ShapeFactory::shell({face.value()});
  if (!shell.ok()) return shell;
  return ShapeFactory::solid({shell.value()});
}

}  // namespace csgtile::kernel
