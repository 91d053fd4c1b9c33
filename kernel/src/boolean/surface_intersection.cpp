#include "boolean/surface_intersection.h"

#include "boolean/marching.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <numbers>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "boolean/tolerance.h"
#include "geometry/geometry_internal.h"

namespace csgtile::kernel::detail {

namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();
/// Lines are clipped to the clip box grown by this fraction of the problem size (plus the
/// tolerance), so that the Boolean can trim them to its faces without losing an end.
constexpr double kClipMargin = 0.05;

// ---- Tolerance decisions ------------------------------------------------------------------

/// Every geometric decision of this unit goes through the engine's tolerance model
/// (boolean/tolerance.h): `length` is the world tolerance; `size` the extent over which
/// directions are compared (the clip box's diagonal, or the largest radius when bigger).
/// Parallelism and coplanarity are coincidence questions, decided there within tolerance.
using Decisions = ToleranceModel;

// ---- Surfaces as analytic descriptions ----------------------------------------------------

enum class Kind { Plane, Cylinder, Cone, Sphere, Torus };

const char* kind_name(Kind kind) {
  switch (kind) {
    case Kind::Plane:
      return "plane";
    case Kind::Cylinder:
      return "cylinder";
    case Kind::Cone:
      return "cone";
    case Kind::Sphere:
      return "sphere";
    case Kind::Torus:
      return "torus";
  }
  return "surface";
}

const char* surface_kind_name(SurfaceKind kind) {
  switch (kind) {
    case SurfaceKind::Plane:
      return "plane";
    case SurfaceKind::Cylinder:
      return "cylinder";
    case SurfaceKind::Cone:
      return "cone";
    case SurfaceKind::Sphere:
      return "sphere";
    case SurfaceKind::Torus:
      return "torus";
    case SurfaceKind::Extrusion:
      return "extrusion";
    case SurfaceKind::Revolution:
      return "revolution";
  }
  return "surface";
}

/// A plane, cylinder, cone, sphere or torus with its frame: the parametrisations of
/// surface.h. A cone whose semi-angle is negligible over the problem size is described as
/// the cylinder it is within tolerance (its parametrisation is the same one).
struct Analytic {
  Kind kind = Kind::Plane;
  Frame frame;
  double radius = 0.0;  // cylinder, sphere; cone reference radius; torus minor radius
  double major = 0.0;   // torus
  double sine = 0.0;    // cone: sin φ
  double cosine = 1.0;  // cone: cos φ

  const Vec3& origin() const { return frame.origin; }
  const Vec3& axis() const { return frame.z; }
  /// Whether the surface turns about its own frame's z axis and has no other symmetry
  /// axis to offer (the sphere turns about any line through its centre).
  bool has_axis() const {
    return kind == Kind::Cylinder || kind == Kind::Cone || kind == Kind::Torus;
  }
  Vec3 radial(double u) const { return std::cos(u) * frame.x + std::sin(u) * frame.y; }
  /// Cone apex (v = −r / sin φ).
  Vec3 apex() const { return frame.origin - radius / sine * cosine * frame.z; }
  /// Cone: the direction in which the nappe ρ ≥ 0 opens.
  Vec3 nappe_axis() const { return sine > 0.0 ? frame.z : Vec3(-frame.z); }
  /// Polar angle of the direction w in the frame's xy-plane.
  double angle_of(const Vec3& w) const { return std::atan2(w.dot(frame.y), w.dot(frame.x)); }
};

std::optional<Analytic> describe(const Surface& s) {
  Analytic out;
  switch (s.kind()) {
    case SurfaceKind::Plane:
      out.kind = Kind::Plane;
      out.frame = static_cast<const PlaneSurface&>(s).frame();
      return out;
    case SurfaceKind::Cylinder: {
      const auto& c = static_cast<const CylinderSurface&>(s);
      out.kind = Kind::Cylinder;
      out.frame = c.frame();
      out.radius = c.radius();
      return out;
    }
    case SurfaceKind::Cone: {
      const auto& c = static_cast<const ConeSurface&>(s);
      out.kind = Kind::Cone;
      out.frame = c.frame();
      out.radius = c.reference_radius();
      out.sine = std::sin(c.semi_angle());
      out.cosine = std::cos(c.semi_angle());
      return out;
    }
    case SurfaceKind::Sphere: {
      const auto& c = static_cast<const SphereSurface&>(s);
      out.kind = Kind::Sphere;
      out.frame = c.frame();
      out.radius = c.radius();
      return out;
    }
    case SurfaceKind::Torus: {
      const auto& c = static_cast<const TorusSurface&>(s);
      out.kind = Kind::Torus;
      out.frame = c.frame();
      out.radius = c.minor_radius();
      out.major = c.major_radius();
      return out;
    }
    case SurfaceKind::Extrusion:
    case SurfaceKind::Revolution:
      return std::nullopt;
  }
  return std::nullopt;
}

/// The largest radius: directions are compared over at least this extent, since a circle
/// of that radius is part of the problem whatever the clip box.
double characteristic_radius(const Analytic& s) {
  switch (s.kind) {
    case Kind::Torus:
      return s.major + s.radius;
    case Kind::Plane:
      return 0.0;
    default:
      return std::abs(s.radius);
  }
}

/// Distance from p to the line (origin, unit direction).
double distance_to_line(const Vec3& p, const Vec3& origin, const Vec3& direction) {
  return (p - origin).cross(direction).norm();
}

/// Unit vector along w; w is not zero by the caller's decision.
Vec3 unit(const Vec3& w) { return w / w.norm(); }

bool coincident(const Analytic& a, const Analytic& b, const Decisions& d) {
  if (a.kind != b.kind) return false;
  const Vec3 offset = b.origin() - a.origin();
  switch (a.kind) {
    case Kind::Plane:
      return d.parallel(a.axis(), b.axis()) && d.negligible(a.axis().dot(offset));
    case Kind::Cylinder:
      return d.parallel(a.axis(), b.axis()) &&
             d.negligible(distance_to_line(b.origin(), a.origin(), a.axis())) &&
             d.negligible(a.radius - b.radius);
    case Kind::Cone:
      // One nappe each: the same apex, opening the same way, with the same half-angle.
      return d.negligible((a.apex() - b.apex()).norm()) &&
             d.parallel(a.nappe_axis(), b.nappe_axis()) &&
             a.nappe_axis().dot(b.nappe_axis()) > 0.0 &&
             d.negligible_angle(std::asin(std::abs(a.sine)) - std::asin(std::abs(b.sine)));
    case Kind::Sphere:
      return d.negligible(offset.norm()) && d.negligible(a.radius - b.radius);
    case Kind::Torus:
      return d.negligible(offset.norm()) && d.parallel(a.axis(), b.axis()) &&
             d.negligible(a.major - b.major) && d.negligible(a.radius - b.radius);
  }
  return false;
}

// ---- Output -------------------------------------------------------------------------------

/// Collects section curves restricted to the grown clip box.
class Sections {
 public:
  Sections(const BoundingBox& region, const Decisions& decide) : region_(region), decide_(decide) {}

  /// The line origin + t·direction (unit direction, t = arc length) for t in
  /// [t_min, t_max] ∩ the region; nothing when that is shorter than the tolerance.
  void add_line(const Vec3& origin, const Vec3& direction, double t_min, double t_max,
                bool tangent) {
    if (!BoxRay(origin, direction).clip(region_, t_min, t_max)) return;
    if (!(t_max - t_min > decide_.length)) return;
    curves_.push_back({std::make_shared<LineCurve>(origin, direction),
                       t_min,
                       t_max,
                       false,
                       tangent,
                       {},
                       {},
                       0.0});
  }

  /// The closed curve center + cos t·a + sin t·b, unless its exact bounds miss the region.
  void add_closed(const Vec3& center, const Vec3& a, const Vec3& b, bool tangent) {
    auto curve = std::make_shared<TrigCurve>(center, a, b);
    if (!curve->bounds(0.0, kTwoPi).intersects(region_)) return;
    curves_.push_back({std::move(curve), 0.0, kTwoPi, true, tangent, {}, {}, 0.0});
  }

  const BoundingBox& region() const { return region_; }
  SsiResult result() && { return {SsiKind::Curves, std::move(curves_), {}}; }

 private:
  BoundingBox region_;
  Decisions decide_;
  std::vector<SectionCurve> curves_;
};

SsiResult unsupported(const Analytic& a, const Analytic& b, const std::string& why) {
  return {SsiKind::Unsupported,
          {},
          std::string(kind_name(a.kind)) + "–" + kind_name(b.kind) + ": " + why};
}

SsiResult no_curves() { return {}; }

// ---- Planar (2D) intersections of lines and circles --------------------------------------

/// p + t·d for t in [t_min, t_max], |d| = 1 (rays and full lines).
struct Line2 {
  Vec2 point;
  Vec2 direction;
  double t_min = -kInfinity, t_max = kInfinity;
};
struct Circle2 {
  Vec2 center;
  double radius;
};
struct Hit2 {
  Vec2 point;
  bool tangent;
};
struct Hits2 {
  std::vector<Hit2> points;
  /// The two curves share a piece longer than the tolerance.
  bool overlap = false;
};

double cross2(const Vec2& a, const Vec2& b) { return a.x() * b.y() - a.y() * b.x(); }
Vec2 perp2(const Vec2& a) { return {-a.y(), a.x()}; }

bool in_range(const Line2& l, double t, const Decisions& d) {
  return t >= l.t_min - d.length && t <= l.t_max + d.length;
}

Hits2 intersect(const Line2& a, const Line2& b, const Decisions& d) {
  Hits2 out;
  const double sine = cross2(a.direction, b.direction);
  const Vec2 w = b.point - a.point;
  if (d.negligible_angle(sine)) {
    if (!d.negligible(cross2(w, a.direction))) return out;
    // Collinear: compare b's range in a's parameter with a's own.
    const double base = w.dot(a.direction);
    const double rate = b.direction.dot(a.direction);
    double lo = base + rate * b.t_min, hi = base + rate * b.t_max;
    if (lo > hi) std::swap(lo, hi);
    lo = std::max(lo, a.t_min);
    hi = std::min(hi, a.t_max);
    if (hi - lo > d.length) {
      out.overlap = true;
    } else if (hi >= lo - d.length) {
      out.points.push_back({a.point + 0.5 * (lo + hi) * a.direction, false});
    }
    return out;
  }
  const double t = cross2(w, b.direction) / sine;
  const double s = cross2(w, a.direction) / sine;
  if (in_range(a, t, d) && in_range(b, s, d)) {
    out.points.push_back({a.point + t * a.direction, false});
  }
  return out;
}

Hits2 intersect(const Line2& l, const Circle2& c, const Decisions& d) {
  Hits2 out;
  const double foot = (c.center - l.point).dot(l.direction);
  const Vec2 to_line = l.point + foot * l.direction - c.center;
  const double distance = to_line.norm();
  if (distance > c.radius + d.length) return out;
  if (distance >= c.radius - d.length) {
    // Touching: one contact point, placed on the circle.
    const Vec2 contact =
        distance > 0.0 ? Vec2(c.center + c.radius / distance * to_line) : Vec2(c.center);
    if (in_range(l, foot, d)) out.points.push_back({contact, true});
    return out;
  }
  const double half = std::sqrt(c.radius * c.radius - distance * distance);
  for (double t : {foot - half, foot + half}) {
    if (in_range(l, t, d)) out.points.push_back({l.point + t * l.direction, false});
  }
  return out;
}

Hits2 intersect(const Circle2& c, const Line2& l, const Decisions& d) { return intersect(l, c, d); }

Hits2 intersect(const Circle2& a, const Circle2& b, const Decisions& d) {
  Hits2 out;
  const Vec2 w = b.center - a.center;
  const double distance = w.norm();
  if (d.negligible(distance)) {
    out.overlap = d.negligible(a.radius - b.radius);
    return out;
  }
  const Vec2 e = w / distance;
  if (distance > a.radius + b.radius + d.length) return out;
  if (distance < std::abs(a.radius - b.radius) - d.length) return out;
  if (distance >= a.radius + b.radius - d.length) {
    out.points.push_back({a.center + a.radius * e, true});
    return out;
  }
  if (distance <= std::abs(a.radius - b.radius) + d.length) {
    // Internal contact: on the far side of the smaller circle from the larger's centre.
    const double side = a.radius >= b.radius ? 1.0 : -1.0;
    out.points.push_back({a.center + side * a.radius * e, true});
    return out;
  }
  const double along =
      (distance * distance + a.radius * a.radius - b.radius * b.radius) / (2.0 * distance);
  const double half = std::sqrt(std::max(0.0, a.radius * a.radius - along * along));
  out.points.push_back({a.center + along * e - half * perp2(e), false});
  out.points.push_back({a.center + along * e + half * perp2(e), false});
  return out;
}

// ---- Coaxial surfaces: meridian intersection ---------------------------------------------

/// A common axis of revolution and the basis that circles around it are written in:
/// centre origin + z·direction, a = ρ·x, b = ρ·y.
struct RevolutionAxis {
  Vec3 origin, direction, x, y;
};

RevolutionAxis own_axis(const Analytic& s) { return {s.origin(), s.axis(), s.frame.x, s.frame.y}; }

/// A surface's meridian in the (ρ, z) coordinates of an axis it turns about: ρ is signed
/// (the half-plane ρ < 0 is the opposite meridian half-plane), so a profile and its mirror
/// image ρ → −ρ describe the same surface.
struct Profile {
  bool is_line = true;
  Line2 line;
  Circle2 circle{Vec2::Zero(), 0.0};

  Profile mirrored() const {
    Profile m = *this;
    m.line.point.x() = -m.line.point.x();
    m.line.direction.x() = -m.line.direction.x();
    m.circle.center.x() = -m.circle.center.x();
    return m;
  }
};

Profile profile(const Analytic& s, const RevolutionAxis& axis) {
  Profile p;
  const double height = (s.origin() - axis.origin).dot(axis.direction);
  switch (s.kind) {
    case Kind::Plane: {
      // Where the axis pierces the plane.
      const double h = s.axis().dot(s.origin() - axis.origin) / s.axis().dot(axis.direction);
      p.line = {Vec2(0.0, h), Vec2(1.0, 0.0)};
      break;
    }
    case Kind::Cylinder:
      p.line = {Vec2(s.radius, height), Vec2(0.0, 1.0)};
      break;
    case Kind::Cone: {
      // ρ = r + v·sin φ, z = height ± v·cos φ with t = v; only the nappe ρ ≥ 0 exists.
      const double up = s.axis().dot(axis.direction) > 0.0 ? 1.0 : -1.0;
      p.line = {Vec2(s.radius, height), Vec2(s.sine, up * s.cosine)};
      const double apex = -s.radius / s.sine;
      if (s.sine > 0.0) {
        p.line.t_min = apex;
      } else {
        p.line.t_max = apex;
      }
      break;
    }
    case Kind::Sphere:
      p.is_line = false;
      p.circle = {Vec2(0.0, height), s.radius};
      break;
    case Kind::Torus:
      p.is_line = false;
      p.circle = {Vec2(s.major, height), s.radius};
      break;
  }
  return p;
}

Hits2 intersect(const Profile& a, const Profile& b, const Decisions& d) {
  if (a.is_line) return b.is_line ? intersect(a.line, b.line, d) : intersect(a.line, b.circle, d);
  return b.is_line ? intersect(a.circle, b.line, d) : intersect(a.circle, b.circle, d);
}

/// Circles where two surfaces of revolution about `axis` meet: the meridian of `a` against
/// the meridian of `b` and its mirror image, each meeting point (ρ, z) one full circle.
/// Points on the axis are contacts, not curves.
SsiResult coaxial_sections(const Analytic& a, const Analytic& b, const RevolutionAxis& axis,
                           const Decisions& d, Sections& out) {
  const Profile pa = profile(a, axis);
  const Profile pb = profile(b, axis);
  std::vector<Hit2> hits;
  for (const Profile& q : {pb, pb.mirrored()}) {
    const Hits2 h = intersect(pa, q, d);
    if (h.overlap) return {SsiKind::Coincident, {}, {}};
    hits.insert(hits.end(), h.points.begin(), h.points.end());
  }
  // Fold onto ρ ≥ 0 and merge the copies the mirror produces.
  std::vector<Hit2> circles;
  for (Hit2 h : hits) {
    h.point.x() = std::abs(h.point.x());
    if (d.negligible(h.point.x())) continue;
    auto same = std::find_if(circles.begin(), circles.end(), [&](const Hit2& c) {
      return d.negligible((c.point - h.point).norm());
    });
    if (same == circles.end()) {
      circles.push_back(h);
    } else {
      same->tangent = same->tangent || h.tangent;
    }
  }
  std::sort(circles.begin(), circles.end(), [](const Hit2& l, const Hit2& r) {
    return l.point.y() != r.point.y() ? l.point.y() < r.point.y() : l.point.x() < r.point.x();
  });
  for (const Hit2& c : circles) {
    const double rho = c.point.x();
    out.add_closed(axis.origin + c.point.y() * axis.direction, rho * axis.x, rho * axis.y,
                   c.tangent);
  }
  return std::move(out).result();
}

/// Whether `s` turns about the line (origin, unit direction): a plane perpendicular to it,
/// a sphere centred on it, or a cylinder, cone or torus with it as axis.
bool turns_about(const Analytic& s, const Vec3& origin, const Vec3& direction, const Decisions& d) {
  switch (s.kind) {
    case Kind::Plane:
      return d.parallel(s.axis(), direction);
    case Kind::Sphere:
      return d.negligible(distance_to_line(s.origin(), origin, direction));
    default:
      return d.parallel(s.axis(), direction) &&
             d.negligible(distance_to_line(s.origin(), origin, direction));
  }
}

/// A sphere whose own frame turns about the (centre) line along `direction`.
bool sphere_frame_along(const Analytic& s, const Vec3& direction, const Decisions& d) {
  return s.kind == Kind::Sphere && d.parallel(s.axis(), direction);
}

/// The common axis of revolution of a and b, if any, with the circle basis the
/// parametrisation contract asks for: surface a's frame when it turns about the axis, then
/// b's, then the plane's, then a frame built around the axis. Plane pairs have none.
std::optional<RevolutionAxis> common_axis(const Analytic& a, const Analytic& b,
                                          const Decisions& d) {
  if (a.has_axis() || b.has_axis()) {
    const Analytic& owner = a.has_axis() ? a : b;
    const Analytic& other = a.has_axis() ? b : a;
    if (!turns_about(other, owner.origin(), owner.axis(), d)) return std::nullopt;
    if (!a.has_axis() && sphere_frame_along(a, owner.axis(), d)) return own_axis(a);
    return own_axis(owner);
  }
  if (a.kind == Kind::Plane && b.kind == Kind::Plane) return std::nullopt;
  if (a.kind == Kind::Sphere && b.kind == Kind::Sphere) {
    const Vec3 w = b.origin() - a.origin();
    if (d.negligible(w.norm())) return std::nullopt;  // concentric: no axis to speak of
    const Vec3 direction = unit(w);
    if (sphere_frame_along(a, direction, d)) return own_axis(a);
    if (sphere_frame_along(b, direction, d)) return own_axis(b);
    const Frame f = Frame::from_z(a.origin(), direction);
    return RevolutionAxis{f.origin, f.z, f.x, f.y};
  }
  // A plane and a sphere: the normal through the centre.
  const Analytic& plane = a.kind == Kind::Plane ? a : b;
  const Analytic& sphere = a.kind == Kind::Plane ? b : a;
  if (sphere_frame_along(sphere, plane.axis(), d)) return own_axis(sphere);
  return RevolutionAxis{sphere.origin(), plane.axis(), plane.frame.x, plane.frame.y};
}

// ---- Pairs --------------------------------------------------------------------------------

SsiResult plane_plane(const Analytic& a, const Analytic& b, const Decisions& d, Sections& out) {
  const Vec3& na = a.axis();
  const Vec3& nb = b.axis();
  if (d.parallel(na, nb)) return no_curves();  // coincidence was ruled out before
  const Vec3 direction = unit(na.cross(nb));
  // The point of the line closest to the region's centre: three planes' intersection.
  const Vec3 centre = 0.5 * (out.region().min + out.region().max);
  const double ha = na.dot(a.origin()), hb = nb.dot(b.origin()), hd = direction.dot(centre);
  const Vec3 point = (ha * nb.cross(direction) + hb * direction.cross(na) + hd * na.cross(nb)) /
                     na.dot(nb.cross(direction));
  out.add_line(point, direction, -kInfinity, kInfinity, false);
  return std::move(out).result();
}

/// The section of cylinder `c` by the plane through `point` with unit normal n (not parallel
/// to the axis), parametrised by the cylinder's angle: C(t) = S(t, v(t)).
void add_oblique_cylinder_section(const Analytic& c, const Vec3& n, const Vec3& point,
                                  Sections& out) {
  const Frame& f = c.frame;
  const double nz = n.dot(f.z);
  const double v0 = n.dot(point - f.origin) / nz;
  const Vec3 a = c.radius * f.x - (c.radius * n.dot(f.x) / nz) * f.z;
  const Vec3 b = c.radius * f.y - (c.radius * n.dot(f.y) / nz) * f.z;
  out.add_closed(f.origin + v0 * f.z, a, b, false);
}

/// Generatrices of cylinder `c` through the cross-section points `hits` (in the frame's
/// (x, y) coordinates): C(t) = S(u, t).
void add_cylinder_lines(const Analytic& c, const std::vector<Hit2>& hits, Sections& out) {
  for (const Hit2& h : hits) {
    const double u = std::atan2(h.point.y(), h.point.x());
    out.add_line(c.origin() + c.radius * c.radial(u), c.axis(), -kInfinity, kInfinity, h.tangent);
  }
}

SsiResult plane_cylinder(const Analytic& p, const Analytic& c, const Decisions& d, Sections& out) {
  const Vec3& n = p.axis();
  if (!d.perpendicular(n, c.axis())) {
    add_oblique_cylinder_section(c, n, p.origin(), out);
    return std::move(out).result();
  }
  // The plane is parallel to the axis: its trace on the cross-section against the circle.
  const Vec2 normal(n.dot(c.frame.x), n.dot(c.frame.y));
  const double length = normal.norm();
  const Vec2 unit_normal = normal / length;
  const double offset = n.dot(p.origin() - c.origin()) / length;
  const Line2 trace{offset * unit_normal, perp2(unit_normal)};
  add_cylinder_lines(c, intersect(trace, Circle2{Vec2::Zero(), c.radius}, d).points, out);
  return std::move(out).result();
}

SsiResult plane_cone(const Analytic& p, const Analytic& k, const Decisions& d, Sections& out) {
  const Vec3& n = p.axis();
  const Vec3 apex = k.apex();
  const double apex_height = n.dot(apex - p.origin());
  // Along the nappe's rays |sin φ|·e(u) + cos φ·k the plane's normal component spans
  // cos φ·(n·k) ± |sin φ|·m, m = |n projected on the frame's xy-plane|.
  const double m = std::hypot(n.dot(k.frame.x), n.dot(k.frame.y));
  const double along_axis = k.cosine * n.dot(k.nappe_axis());
  const double spread = std::abs(k.sine) * m;
  if (!d.negligible(apex_height)) {
    const bool away = apex_height > 0.0 ? along_axis - spread >= 0.0 : along_axis + spread <= 0.0;
    if (away) return no_curves();
    return unsupported(p, k, "section not through the apex (conic) not supported yet");
  }
  // Through the apex: generatrices S(u, ·) whose direction ∂S/∂v = sin φ·e(u) + cos φ·z lies
  // in the plane, i.e. sin φ·m·cos(u − ψ) = −cos φ·(n·z).
  const double psi = std::atan2(n.dot(k.frame.y), n.dot(k.frame.x));
  const double rhs = -k.cosine * n.dot(k.axis());
  const double amplitude = k.sine * m;
  std::vector<std::pair<double, bool>> angles;  // u, tangent
  if (d.negligible_angle(std::abs(amplitude) - std::abs(rhs))) {
    angles.emplace_back(rhs / amplitude > 0.0 ? psi : psi + kPi, true);
  } else if (std::abs(amplitude) > std::abs(rhs)) {
    const double alpha = std::acos(rhs / amplitude);
    angles.emplace_back(psi - alpha, false);
    angles.emplace_back(psi + alpha, false);
  }
  const double v_apex = -k.radius / k.sine;
  for (const auto& [u, tangent] : angles) {
    const Vec3 origin = k.origin() + k.radius * k.radial(u);
    const Vec3 direction = k.sine * k.radial(u) + k.cosine * k.axis();
    out.add_line(origin, direction, k.sine > 0.0 ? v_apex : -kInfinity,
                 k.sine > 0.0 ? kInfinity : v_apex, tangent);
  }
  return std::move(out).result();
}

/// The meridian circles C(t) = S(u, t) of a sphere or torus for u = u0 and u0 + π, where the
/// plane with normal n contains the axis.
void add_meridians(const Analytic& s, const Vec3& n, Sections& out) {
  const double u0 = s.angle_of(s.axis().cross(n));
  for (double u : {u0, u0 + kPi}) {
    const Vec3 e = s.radial(u);
    out.add_closed(s.origin() + s.major * e, s.radius * e, s.radius * s.axis(), false);
    if (s.kind == Kind::Sphere) break;  // one great circle holds both meridians
  }
}

SsiResult plane_sphere_meridian(const Analytic& p, const Analytic& s, Sections& out) {
  add_meridians(s, p.axis(), out);
  return std::move(out).result();
}

SsiResult plane_torus(const Analytic& p, const Analytic& t, const Decisions& d, Sections& out) {
  const Vec3& n = p.axis();
  const double height = n.dot(t.origin() - p.origin());
  // Support of the torus along n: R·|n × z| + r; at that distance the plane touches it at a
  // point (the plane ⊥ axis case is coaxial and handled before).
  const double reach = t.major * n.cross(t.axis()).norm() + t.radius;
  if (std::abs(height) >= reach - d.length) return no_curves();
  if (d.perpendicular(n, t.axis()) && d.negligible(height)) {
    add_meridians(t, n, out);
    return std::move(out).result();
  }
  return unsupported(p, t, "section oblique to the axis (spiric curve) not supported yet");
}

SsiResult cylinder_cylinder(const Analytic& a, const Analytic& b, const Decisions& d,
                            Sections& out) {
  if (d.parallel(a.axis(), b.axis())) {
    // Cross-section in a's frame; coaxial pairs were handled before.
    const Vec3 w = b.origin() - a.origin();
    const Circle2 cb{Vec2(w.dot(a.frame.x), w.dot(a.frame.y)), b.radius};
    add_cylinder_lines(a, intersect(Circle2{Vec2::Zero(), a.radius}, cb, d).points, out);
    return std::move(out).result();
  }
  // Closest points of the two axes.
  const Vec3& za = a.axis();
  const Vec3& zb = b.axis();
  const Vec3 w = a.origin() - b.origin();
  const double c = za.dot(zb), da = za.dot(w), db = zb.dot(w);
  const double denominator = 1.0 - c * c;
  const Vec3 pa = a.origin() + ((c * db - da) / denominator) * za;
  const Vec3 pb = b.origin() + ((db - c * da) / denominator) * zb;
  const double gap = (pa - pb).norm();
  if (gap >= a.radius + b.radius - d.length) return no_curves();  // apart, or a point contact
  if (!d.negligible(gap)) {
    return unsupported(a, b, "skew axes: general quartic, not supported yet");
  }
  if (!d.negligible(a.radius - b.radius)) {
    return unsupported(a, b, "crossing axes with different radii: quartic, not supported yet");
  }
  // Equal radii, crossing axes: the two planes through the crossing point bisecting the
  // axes (normals z_a ∓ z_b) each cut both cylinders in the same ellipse.
  const Vec3 crossing = 0.5 * (pa + pb);
  add_oblique_cylinder_section(a, unit(za - zb), crossing, out);
  add_oblique_cylinder_section(a, unit(za + zb), crossing, out);
  return std::move(out).result();
}

SsiResult cylinder_sphere(const Analytic& c, const Analytic& s, const Decisions& d) {
  const double offset = distance_to_line(s.origin(), c.origin(), c.axis());
  // Apart or touching outside; or the ball inside the cylinder, touching at most.
  if (offset >= c.radius + s.radius - d.length) return no_curves();
  if (offset + s.radius <= c.radius + d.length) return no_curves();
  return unsupported(c, s, "sphere centre off the axis: quartic, not supported yet");
}

SsiResult sphere_torus(const Analytic& s, const Analytic& t, const Decisions& d) {
  // Distances from the sphere's centre to the torus' core circle, nearest and farthest.
  const Vec3 q = s.origin() - t.origin();
  const double z = q.dot(t.axis());
  const double rho = (q - z * t.axis()).norm();
  const double near = std::hypot(rho - t.major, z);
  const double far = std::hypot(rho + t.major, z);
  const bool apart = near >= s.radius + t.radius - d.length;
  const bool tube_inside_ball = far + t.radius <= s.radius + d.length;
  const bool ball_inside_tube = near + s.radius <= t.radius + d.length;
  if (apart || tube_inside_ball || ball_inside_tube) return no_curves();
  return unsupported(s, t, "sphere centre off the axis: not supported yet");
}

/// Whether the surface misses the ball around the region (a conservative test through the
/// exact point inversion of every kind handled here).
bool misses(const Surface& s, const BoundingBox& region, const Decisions& d) {
  const Vec3 centre = 0.5 * (region.min + region.max);
  const double half_diagonal = 0.5 * (region.max - region.min).norm();
  const Vec2 uv = s.closest_parameters(centre);
  return (s.point(uv.x(), uv.y()) - centre).norm() > half_diagonal + d.length;
}

SsiResult dispatch(const Analytic& a, const Analytic& b, const Decisions& d, Sections& out) {
  if (a.kind == Kind::Plane && b.kind == Kind::Plane) return plane_plane(a, b, d, out);
  // A plane through a sphere's own axis: the great circle S(u0, ·).
  for (const auto& [p, s] : {std::pair{&a, &b}, std::pair{&b, &a}}) {
    if (p->kind == Kind::Plane && s->kind == Kind::Sphere &&
        d.perpendicular(p->axis(), s->axis()) &&
        d.negligible(p->axis().dot(s->origin() - p->origin()))) {
      return plane_sphere_meridian(*p, *s, out);
    }
  }
  if (const std::optional<RevolutionAxis> axis = common_axis(a, b, d)) {
    return coaxial_sections(a, b, *axis, d, out);
  }
  // The rest in the order plane < cylinder < cone < sphere < torus (a first on ties).
  const bool swap = b.kind < a.kind;
  const Analytic& first = swap ? b : a;
  const Analytic& second = swap ? a : b;
  switch (first.kind) {
    case Kind::Plane:
      switch (second.kind) {
        case Kind::Cylinder:
          return plane_cylinder(first, second, d, out);
        case Kind::Cone:
          return plane_cone(first, second, d, out);
        case Kind::Torus:
          return plane_torus(first, second, d, out);
        default:
          break;
      }
      break;
    case Kind::Cylinder:
      if (second.kind == Kind::Cylinder) return cylinder_cylinder(first, second, d, out);
      if (second.kind == Kind::Sphere) return cylinder_sphere(first, second, d);
      break;
    case Kind::Sphere:
      // Distinct centres are always coaxial; concentric spheres of different radii.
      if (second.kind == Kind::Sphere) return no_curves();
      if (second.kind == Kind::Torus) return sphere_torus(first, second, d);
      break;
    default:
      break;
  }
  return unsupported(first, second, "axes not common: general quartic, not supported yet");
}

// Sections without a closed form, traced (marching.h): polylines with their pcurves, chords
// within traced_sag(tolerance, size) of the exact curve (boolean/tolerance.h).
SsiResult traced_sections(const Surface& a, const Surface& b, const BoundingBox& region,
                          double tolerance, double size) {
  const double sag = traced_sag(tolerance, size);
  MarchResult marched = march_intersection(a, b, region, tolerance, sag);
  if (!marched.ok) {
    return {SsiKind::Unsupported,
            {},
            std::string(surface_kind_name(a.kind())) + "–" + surface_kind_name(b.kind()) +
                ": no closed form, and tracing stopped: " + marched.reason};
  }
  // A sphere's v stays within its poles; a branch beyond them went through a pole, where its
  // pcurve would have to jump (the Boolean turns a sphere's poles away from the other
  // operand's faces so that this does not happen).
  for (const auto& [surface, which] : {std::pair{&a, 0}, std::pair{&b, 1}}) {
    if (surface->kind() != SurfaceKind::Sphere) continue;
    for (const MarchedCurve& m : marched.curves) {
      for (const Vec2& uv : which == 0 ? m.uv_a : m.uv_b) {
        if (std::abs(uv.y()) > 0.5 * std::numbers::pi + kParamRelative) {
          return {SsiKind::Unsupported,
                  {},
                  std::string(surface_kind_name(a.kind())) + "–" + surface_kind_name(b.kind()) +
                      ": no closed form, and the traced section passes a pole of the sphere"};
        }
      }
    }
  }
  SsiResult result;
  for (MarchedCurve& m : marched.curves) {
    SectionCurve c;
    const double deviation = std::max(m.deviation, tolerance);
    c.first = 0.0;
    c.last = static_cast<double>(m.points.size() - 1);
    c.closed = m.closed;
    c.curve = std::make_shared<PolylineCurve>(std::move(m.points), deviation);
    c.pcurve_a = std::make_shared<Polyline2d>(std::move(m.uv_a));
    c.pcurve_b = std::make_shared<Polyline2d>(std::move(m.uv_b));
    c.deviation = deviation;
    result.curves.push_back(std::move(c));
  }
  return result;
}

}  // namespace

SsiResult intersect_surfaces(const Surface& a, const Surface& b, const BoundingBox& clip,
                             double tolerance) {
  std::optional<Analytic> da = describe(a);
  std::optional<Analytic> db = describe(b);
  if (!da || !db) {
    if (clip.empty()) return no_curves();
    const double size = std::max(clip.size().norm(), tolerance);
    BoundingBox region = clip;
    region.enlarge(kClipMargin * size + tolerance);
    return traced_sections(a, b, region, tolerance, size);
  }
  const double size = std::max({clip.empty() ? 0.0 : clip.size().norm(), characteristic_radius(*da),
                                characteristic_radius(*db), tolerance});
  const Decisions decide{tolerance, size};
  // A cone this close to its cylinder is that cylinder within tolerance, with the same
  // parametrisation.
  for (Analytic* s : {&*da, &*db}) {
    if (s->kind == Kind::Cone && decide.negligible_angle(s->sine)) s->kind = Kind::Cylinder;
  }
  if (coincident(*da, *db, decide)) return {SsiKind::Coincident, {}, {}};
  if (clip.empty()) return no_curves();
  BoundingBox region = clip;
  region.enlarge(kClipMargin * size + tolerance);
  if (misses(a, region, decide) || misses(b, region, decide)) return no_curves();
  Sections out(region, decide);
  SsiResult result = dispatch(*da, *db, decide, out);
  if (result.kind == SsiKind::Unsupported) result = traced_sections(a, b, region, tolerance, size);
  return result;
}

}  // namespace csgtile::kernel::detail
