// structurally_equal: walks both shapes in lockstep, pairing bodies and geometry objects.
// A pairing must be one-to-one in both directions, which is exactly "sharing preserved";
// each pair is compared once, so the walk is linear. Numbers compare by their bits.

#include <cstdint>
#include <unordered_map>
#include <utility>
#include <vector>

#include "csgtile/kernel/native_format.h"
#include "io/byte_stream.h"

namespace csgtile::kernel {

namespace {

using detail::double_bits;

bool same(double a, double b) { return double_bits(a) == double_bits(b); }

template <class V>
bool same_vector(const V& a, const V& b) {
  for (int i = 0; i < a.size(); ++i) {
    if (!same(a[i], b[i])) return false;
  }
  return true;
}

bool same_frame(const Frame& a, const Frame& b) {
  return same_vector(a.origin, b.origin) && same_vector(a.x, b.x) && same_vector(a.y, b.y) &&
         same_vector(a.z, b.z);
}

bool same_location(const Location& a, const Location& b) {
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      if (!same(a.rotation()(i, j), b.rotation()(i, j))) return false;
    }
  }
  return same(a.scale(), b.scale()) && same_vector(a.translation(), b.translation());
}

/// A one-to-one pairing of objects of `a` with objects of `b`.
class Pairing {
 public:
  enum class Outcome { New, Known, Conflict };
  Outcome pair(const void* a, const void* b) {
    const auto forward = forward_.find(a);
    const auto backward = backward_.find(b);
    if (forward == forward_.end() && backward == backward_.end()) {
      forward_.emplace(a, b);
      backward_.emplace(b, a);
      return Outcome::New;
    }
    if (forward != forward_.end() && forward->second == b) return Outcome::Known;
    return Outcome::Conflict;
  }

 private:
  std::unordered_map<const void*, const void*> forward_, backward_;
};

class Comparer {
 public:
  bool shapes(const Shape& a, const Shape& b) {
    if (a.is_null() || b.is_null()) return a.is_null() && b.is_null();
    if (!reference(a, b)) return false;
    while (!pending_.empty()) {
      const auto [body_a, body_b] = pending_.back();
      pending_.pop_back();
      if (!bodies(*body_a, *body_b)) return false;
    }
    return true;
  }

 private:
  /// Same location and orientation, and bodies paired (queued for comparison when new).
  bool reference(const Shape& a, const Shape& b) {
    if (a.orientation() != b.orientation() || !same_location(a.location(), b.location())) {
      return false;
    }
    switch (bodies_.pair(&a.body(), &b.body())) {
      case Pairing::Outcome::New:
        pending_.emplace_back(&a.body(), &b.body());
        return true;
      case Pairing::Outcome::Known:
        return true;
      case Pairing::Outcome::Conflict:
        return false;
    }
    return false;
  }

  bool bodies(const ShapeBody& a, const ShapeBody& b) {
    if (a.kind() != b.kind() || a.children().size() != b.children().size()) return false;
    for (std::size_t i = 0; i < a.children().size(); ++i) {
      if (!reference(a.children()[i], b.children()[i])) return false;
    }
    if ((a.vertex() == nullptr) != (b.vertex() == nullptr) ||
        (a.edge() == nullptr) != (b.edge() == nullptr) ||
        (a.face() == nullptr) != (b.face() == nullptr)) {
      return false;
    }
    if (a.vertex() != nullptr) {
      return same_vector(a.vertex()->point, b.vertex()->point) &&
             same(a.vertex()->tolerance, b.vertex()->tolerance);
    }
    if (a.edge() != nullptr) {
      const EdgeData& ea = *a.edge();
      const EdgeData& eb = *b.edge();
      if (!same(ea.first, eb.first) || !same(ea.last, eb.last) ||
          !same(ea.tolerance, eb.tolerance)) {
        return false;
      }
      if (ea.degenerate() || eb.degenerate()) return ea.degenerate() && eb.degenerate();
      return curves(*ea.curve, *eb.curve);
    }
    if (a.face() != nullptr) {
      const FaceData& fa = *a.face();
      const FaceData& fb = *b.face();
      if (!same(fa.tolerance, fb.tolerance) || !surfaces(*fa.surface, *fb.surface) ||
          fa.pcurves.size() != fb.pcurves.size()) {
        return false;
      }
      for (std::size_t w = 0; w < fa.pcurves.size(); ++w) {
        if (fa.pcurves[w].size() != fb.pcurves[w].size()) return false;
        for (std::size_t e = 0; e < fa.pcurves[w].size(); ++e) {
          if (!pcurves(*fa.pcurves[w][e], *fb.pcurves[w][e])) return false;
        }
      }
    }
    return true;
  }

  bool curves(const Curve& a, const Curve& b) {
    switch (curves_.pair(&a, &b)) {
      case Pairing::Outcome::Known:
        return true;
      case Pairing::Outcome::Conflict:
        return false;
      case Pairing::Outcome::New:
        break;
    }
    if (a.kind() != b.kind()) return false;
    switch (a.kind()) {
      case CurveKind::Line: {
        const auto& la = static_cast<const LineCurve&>(a);
        const auto& lb = static_cast<const LineCurve&>(b);
        return same_vector(la.origin(), lb.origin()) && same_vector(la.direction(), lb.direction());
      }
      case CurveKind::Circle: {
        const auto& ca = static_cast<const CircleCurve&>(a);
        const auto& cb = static_cast<const CircleCurve&>(b);
        return same_frame(ca.frame(), cb.frame()) && same(ca.radius(), cb.radius());
      }
      case CurveKind::Ellipse: {
        const auto& ea = static_cast<const EllipseCurve&>(a);
        const auto& eb = static_cast<const EllipseCurve&>(b);
        return same_frame(ea.frame(), eb.frame()) && same(ea.major_radius(), eb.major_radius()) &&
               same(ea.minor_radius(), eb.minor_radius());
      }
      case CurveKind::Polyline: {
        const auto& pa = static_cast<const PolylineCurve&>(a);
        const auto& pb = static_cast<const PolylineCurve&>(b);
        if (!same(pa.tolerance(), pb.tolerance()) || pa.points().size() != pb.points().size()) {
          return false;
        }
        for (std::size_t i = 0; i < pa.points().size(); ++i) {
          if (!same_vector(pa.points()[i], pb.points()[i])) return false;
        }
        return true;
      }
      case CurveKind::Trig: {
        const auto& ta = static_cast<const TrigCurve&>(a);
        const auto& tb = static_cast<const TrigCurve&>(b);
        return same_vector(ta.center(), tb.center()) && same_vector(ta.a(), tb.a()) &&
               same_vector(ta.b(), tb.b());
      }
    }
    return false;
  }

  bool surfaces(const Surface& a, const Surface& b) {
    switch (surfaces_.pair(&a, &b)) {
      case Pairing::Outcome::Known:
        return true;
      case Pairing::Outcome::Conflict:
        return false;
      case Pairing::Outcome::New:
        break;
    }
    if (a.kind() != b.kind()) return false;
    switch (a.kind()) {
      case SurfaceKind::Plane:
        return same_frame(static_cast<const PlaneSurface&>(a).frame(),
                          static_cast<const PlaneSurface&>(b).frame());
      case SurfaceKind::Cylinder: {
        const auto& ca = static_cast<const CylinderSurface&>(a);
        const auto& cb = static_cast<const CylinderSurface&>(b);
        return same_frame(ca.frame(), cb.frame()) && same(ca.radius(), cb.radius());
      }
      case SurfaceKind::Cone: {
        const auto& ca = static_cast<const ConeSurface&>(a);
        const auto& cb = static_cast<const ConeSurface&>(b);
        return same_frame(ca.frame(), cb.frame()) &&
               same(ca.reference_radius(), cb.reference_radius()) &&
               same(ca.semi_angle(), cb.semi_angle());
      }
      case SurfaceKind::Sphere: {
        const auto& sa = static_cast<const SphereSurface&>(a);
        const auto& sb = static_cast<const SphereSurface&>(b);
        return same_frame(sa.frame(), sb.frame()) && same(sa.radius(), sb.radius());
      }
      case SurfaceKind::Torus: {
        const auto& ta = static_cast<const TorusSurface&>(a);
        const auto& tb = static_cast<const TorusSurface&>(b);
        return same_frame(ta.frame(), tb.frame()) && same(ta.major_radius(), tb.major_radius()) &&
               same(ta.minor_radius(), tb.minor_radius());
      }
      case SurfaceKind::Extrusion: {
        const auto& ea = static_cast<const ExtrusionSurface&>(a);
        const auto& eb = static_cast<const ExtrusionSurface&>(b);
        return same_vector(ea.direction(), eb.direction()) && curves(*ea.basis(), *eb.basis());
      }
      case SurfaceKind::Revolution: {
        const auto& ra = static_cast<const RevolutionSurface&>(a);
        const auto& rb = static_cast<const RevolutionSurface&>(b);
        return same_vector(ra.axis_origin(), rb.axis_origin()) &&
               same_vector(ra.axis_direction(), rb.axis_direction()) &&
               curves(*ra.meridian(), *rb.meridian());
      }
    }
    return false;
  }

  bool pcurves(const Curve2d& a, const Curve2d& b) {
    switch (pcurves_.pair(&a, &b)) {
      case Pairing::Outcome::Known:
        return true;
      case Pairing::Outcome::Conflict:
        return false;
      case Pairing::Outcome::New:
        break;
    }
    if (a.kind() != b.kind()) return false;
    switch (a.kind()) {
      case Curve2dKind::Line: {
        const auto& la = static_cast<const Line2d&>(a);
        const auto& lb = static_cast<const Line2d&>(b);
        return same_vector(la.origin(), lb.origin()) && same_vector(la.direction(), lb.direction());
      }
      case Curve2dKind::Circle: {
        const auto& ca = static_cast<const Circle2d&>(a);
        const auto& cb = static_cast<const Circle2d&>(b);
        return same_vector(ca.center(), cb.center()) && same(ca.radius(), cb.radius()) &&
               ca.sense() == cb.sense();
      }
      case Curve2dKind::Polyline: {
        const auto& pa = static_cast<const Polyline2d&>(a);
        const auto& pb = static_cast<const Polyline2d&>(b);
        if (pa.points().size() != pb.points().size()) return false;
        for (std::size_t i = 0; i < pa.points().size(); ++i) {
          if (!same_vector(pa.points()[i], pb.points()[i])) return false;
        }
        return true;
      }
      case Curve2dKind::Trig: {
        const auto& ta = static_cast<const Trig2d&>(a);
        const auto& tb = static_cast<const Trig2d&>(b);
        return same_vector(ta.c(), tb.c()) && same_vector(ta.a(), tb.a()) &&
               same_vector(ta.b(), tb.b()) && same_vector(ta.d(), tb.d());
      }
    }
    return false;
  }

  Pairing bodies_, curves_, surfaces_, pcurves_;
  std::vector<std::pair<const ShapeBody*, const ShapeBody*>> pending_;
};

}  // namespace

bool structurally_equal(const Shape& a, const Shape& b) { return Comparer().shapes(a, b); }

}  // namespace csgtile::kernel
