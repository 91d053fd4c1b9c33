// Exact first crossings of a ray with the boundary of one primitive, in the primitive's local
// frame (scene-format.md). Every primitive's boundary is a union of pieces — planes bounded by
// polygons or circles, quadric sides x² + y² = (a + k·z)² bounded in z, a sphere, a torus —
// and the first crossing is the nearest admissible crossing over all pieces. That is right
// whether the ray starts outside (it enters) or inside (it leaves).
//
// Precision: the ray is first moved along itself to the point nearest the primitive's centre,
// so the equations are solved with small coordinates whether the scanner is 2 m or 500 m
// away; the quadratics and the torus quartic are solved by the kernel's root finders
// (csgtile/kernel/polynomial.h: cancellation-free, a root within rounding of a tangency once),
// the torus's roots then polished by Newton steps on the (1-Lipschitz) distance to the torus.

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

#include "csgtile/kernel/polygon2d.h"
#include "csgtile/kernel/polynomial.h"

#include "synth/ray_internal.h"

namespace csgtile::geo::detail {

namespace {

using kernel::PrimitiveType;
using kernel::Vec2;
using kernel::Vec3;

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kTwoPi = 2.0 * std::numbers::pi;

// The nearest admissible crossing found so far; crossings count in (lo, hi].
struct Nearest {
  double lo;
  double hi;
  double s = kInf;
  Vec3 normal = Vec3::Zero();

  bool admissible(double sigma) const { return sigma > lo && sigma <= hi && sigma < s; }
  void offer(double sigma, const Vec3& n) {
    if (admissible(sigma)) {
      s = sigma;
      normal = n;
    }
  }
};

// The angular limits of a partial revolution: φ = atan2(y, x) in [0, angle].
struct TurnLimit {
  double angle = kTwoPi;
  double slack = 0.0;  // local length; points this close to the axis are on both end faces

  bool contains(const Vec3& p) const {
    if (angle >= kTwoPi) return true;
    if (std::hypot(p.x(), p.y()) <= slack) return true;
    double phi = std::atan2(p.y(), p.x());
    if (phi < 0.0) phi += kTwoPi;
    constexpr double kAngleSlack = 1e-12;
    return phi <= angle + kAngleSlack || phi >= kTwoPi - kAngleSlack;
  }
};

// A quadric side x² + y² = (a + k·z)² between z0 and z1 (where a + k·z >= 0): cylinders
// (k = 0), cones, frustums and the sloped pieces of revolutions.
void offer_quadric_side(const Vec3& o, const Vec3& u, double a, double k, double z0, double z1,
                        double slack, const TurnLimit& turn, Nearest& best) {
  const double w = a + k * o.z();
  const double qa = u.x() * u.x() + u.y() * u.y() - k * k * u.z() * u.z();
  const double hb = o.x() * u.x() + o.y() * u.y() - k * u.z() * w;
  const double xy2 = o.x() * o.x() + o.y() * o.y();
  std::array<double, 2> roots{};
  bool tangent = false;
  const int n = kernel::solve_quadratic(qa, hb, xy2 - w * w, xy2 + w * w, roots, tangent);
  for (int i = 0; i < n; ++i) {
    const double s = roots[static_cast<std::size_t>(i)];
    if (!best.admissible(s)) continue;
    const Vec3 p = o + s * u;
    if (p.z() < z0 - slack || p.z() > z1 + slack) continue;
    const double radius = a + k * p.z();
    if (radius < -slack) continue;  // the mirrored nappe of the cone
    if (!turn.contains(p)) continue;
    Vec3 n3(p.x(), p.y(), -k * radius);
    if (n3.squaredNorm() == 0.0) n3 = Vec3(0.0, 0.0, k > 0.0 ? -1.0 : 1.0);  // an apex
    best.offer(s, n3);
  }
}

// The plane z = z crossed within the annulus r_in <= ρ <= r_out (r_in = 0: a disc).
void offer_annulus(const Vec3& o, const Vec3& u, double z, double r_in, double r_out, double slack,
                   const TurnLimit& turn, Nearest& best) {
  if (u.z() == 0.0) return;
  const double s = (z - o.z()) / u.z();
  if (!best.admissible(s)) return;
  const Vec3 p = o + s * u;
  const double rho = std::hypot(p.x(), p.y());
  if (rho > r_out + slack || rho < r_in - slack) return;
  if (!turn.contains(p)) return;
  best.offer(s, Vec3::UnitZ());
}

void hit_box(const Vec3& o, const Vec3& u, const Vec3& size, double slack, Nearest& best) {
  for (int i = 0; i < 3; ++i) {
    if (u[i] == 0.0) continue;
    for (double side : {0.0, size[i]}) {
      const double s = (side - o[i]) / u[i];
      if (!best.admissible(s)) continue;
      const Vec3 p = o + s * u;
      const int j = (i + 1) % 3;
      const int k = (i + 2) % 3;
      if (p[j] < -slack || p[j] > size[j] + slack || p[k] < -slack || p[k] > size[k] + slack) {
        continue;
      }
      best.offer(s, Vec3::Unit(i));
    }
  }
}

void hit_sphere(const Vec3& o, const Vec3& u, double r, Nearest& best) {
  std::array<double, 2> roots{};
  bool tangent = false;
  const double o2 = o.squaredNorm();
  const int n = kernel::solve_quadratic(1.0, o.dot(u), o2 - r * r, o2 + r * r, roots, tangent);
  for (int i = 0; i < n; ++i) {
    const double s = roots[static_cast<std::size_t>(i)];
    best.offer(s, o + s * u);
  }
}

// Distance-to-torus minus r (1-Lipschitz) and its gradient: the Newton polish of a hit.
double torus_distance(const Vec3& p, double major, double minor, Vec3* gradient) {
  const double rho = std::hypot(p.x(), p.y());
  const double dr = rho - major;
  const double d = std::hypot(dr, p.z());
  if (gradient != nullptr) {
    if (d == 0.0 || rho == 0.0) {
      *gradient = Vec3::Zero();
    } else {
      *gradient = Vec3(dr / d * p.x() / rho, dr / d * p.y() / rho, p.z() / d);
    }
  }
  return d - minor;
}

void hit_torus(const Vec3& o, const Vec3& u, double major, double minor, Nearest& best) {
  // The ray within the bounding sphere (o is the ray's point nearest the centre).
  const double outer = major + minor;
  const double reach2 = outer * outer - o.squaredNorm();
  if (reach2 < 0.0) return;
  const double reach = std::sqrt(reach2) * (1.0 + 1e-9) + 1e-12 * outer;
  const double lo = std::max(best.lo, -reach);
  const double hi = std::min(std::min(best.hi, best.s), reach);
  if (!(lo < hi)) return;
  // (|p|² + R² − r²)² − 4R²(x² + y²) with p = o + s·u, |u| = 1.
  const double f = o.dot(u);
  const double e = o.squaredNorm() + major * major - minor * minor;
  const double axy = u.x() * u.x() + u.y() * u.y();
  const double bxy = o.x() * u.x() + o.y() * u.y();
  const double cxy = o.x() * o.x() + o.y() * o.y();
  const double r4 = 4.0 * major * major;
  const std::array<double, 5> quartic = {e * e - r4 * cxy, 4.0 * e * f - 2.0 * r4 * bxy,
                                         4.0 * f * f + 2.0 * e - r4 * axy, 4.0 * f, 1.0};
  std::vector<kernel::PolynomialRoot> roots;
  kernel::polynomial_roots(quartic.data(), 4, lo, hi, roots);
  for (const kernel::PolynomialRoot& root : roots) {
    double s = root.x;
    for (int step = 0; step < 3; ++step) {
      Vec3 gradient;
      const double g = torus_distance(o + s * u, major, minor, &gradient);
      const double slope = gradient.dot(u);
      // Only where the ray crosses the surface clearly: near tangency Newton may jump.
      if (std::abs(slope) < 0.05 || std::abs(g / slope) > 1e-6 * outer) break;
      s -= g / slope;
    }
    if (!best.admissible(s)) continue;
    const Vec3 p = o + s * u;
    const double rho = std::hypot(p.x(), p.y());
    Vec3 n3 =
        rho > 0.0 ? Vec3(p.x() - major * p.x() / rho, p.y() - major * p.y() / rho, p.z()) : Vec3(p);
    best.offer(s, n3);
    return;
  }
}

// Calls `f(ring)` for each ring of the section: an extrusion's profile and holes, a
// revolution's profile.
template <typename F>
void for_each_ring(const PreparedPrimitive& p, F&& f) {
  f(p.spec.profile);
  if (p.spec.type != PrimitiveType::Extrusion) return;
  for (const std::vector<Vec2>& hole : p.spec.holes) f(hole);
}

// Calls `f(a, b)` for each edge a→b of the section's rings, ring by ring.
template <typename F>
void for_each_edge(const PreparedPrimitive& p, F&& f) {
  for_each_ring(p, [&](const std::vector<Vec2>& ring) {
    for (std::size_t i = 0; i < ring.size(); ++i) f(ring[i], ring[(i + 1) % ring.size()]);
  });
}

void hit_extrusion(const PreparedPrimitive& p, const Vec3& o, const Vec3& u, Nearest& best) {
  const double h = p.spec.height;
  const double slack = p.slack;
  // Caps: the planes z = 0 and z = h inside the profile.
  if (u.z() != 0.0) {
    for (double z : {0.0, h}) {
      const double s = (z - o.z()) / u.z();
      if (!best.admissible(s)) continue;
      const Vec3 q = o + s * u;
      if (inside_rings(p, Vec2(q.x(), q.y()))) best.offer(s, Vec3::UnitZ());
    }
  }
  // Walls: one vertical plane piece per ring edge.
  const Vec2 o2(o.x(), o.y());
  const Vec2 u2(u.x(), u.y());
  for_each_edge(p, [&](const Vec2& a, const Vec2& b) {
    const Vec2 e = b - a;
    const double den = u2.x() * e.y() - u2.y() * e.x();
    if (den == 0.0) return;
    const Vec2 ao = a - o2;
    const double s = (ao.x() * e.y() - ao.y() * e.x()) / den;
    if (!best.admissible(s)) return;
    const double along = (ao.x() * u2.y() - ao.y() * u2.x()) / den;
    const double length = e.norm();
    if (along * length < -slack || along * length > length + slack) return;
    const double z = o.z() + s * u.z();
    if (z < -slack || z > h + slack) return;
    best.offer(s, Vec3(e.y(), -e.x(), 0.0));
  });
}

void hit_revolution(const PreparedPrimitive& p, const Vec3& o, const Vec3& u, Nearest& best) {
  const double slack = p.slack;
  TurnLimit turn;
  turn.angle = p.partial_turn ? p.spec.angle : kTwoPi;
  turn.slack = slack;
  for_each_edge(p, [&](const Vec2& a, const Vec2& b) {
    const double rho0 = a.x(), z0 = a.y();
    const double rho1 = b.x(), z1 = b.y();
    if (rho0 == 0.0 && rho1 == 0.0) return;  // on the axis: bounds nothing
    if (z0 == z1) {
      offer_annulus(o, u, z0, std::min(rho0, rho1), std::max(rho0, rho1), slack, turn, best);
    } else {
      const double k = (rho1 - rho0) / (z1 - z0);
      offer_quadric_side(o, u, rho0 - k * z0, k, std::min(z0, z1), std::max(z0, z1), slack, turn,
                         best);
    }
  });
  if (!p.partial_turn) return;
  // End faces: the profile itself in the half-planes φ = 0 and φ = angle.
  for (double phi : {0.0, p.spec.angle}) {
    const Vec3 radial(std::cos(phi), std::sin(phi), 0.0);
    const Vec3 normal(-radial.y(), radial.x(), 0.0);
    const double den = u.dot(normal);
    if (den == 0.0) continue;
    const double s = -o.dot(normal) / den;
    if (!best.admissible(s)) continue;
    const Vec3 q = o + s * u;
    const double rho = q.dot(radial);
    if (rho < -slack) continue;
    if (inside_rings(p, Vec2(std::max(rho, 0.0), q.z()))) best.offer(s, normal);
  }
}

}  // namespace

bool inside_rings(const PreparedPrimitive& p, const Vec2& q) {
  bool inside = false;
  for_each_ring(
      p, [&](const std::vector<Vec2>& ring) { inside = inside != kernel::inside_ring(q, ring); });
  return inside;
}

PreparedPrimitive prepare_primitive(const kernel::PrimitiveSpec& spec) {
  PreparedPrimitive p;
  p.spec = spec;
  p.rotation_transposed = spec.placement.rotation().transpose();
  p.scale = spec.placement.scale();
  p.translation = spec.placement.translation();
  kernel::BoundingBox& b = p.local_bounds;
  switch (spec.type) {
    case PrimitiveType::Box:
      b.add(Vec3::Zero());
      b.add(spec.size);
      break;
    case PrimitiveType::Cylinder:
      b.add(Vec3(-spec.radius, -spec.radius, 0.0));
      b.add(Vec3(spec.radius, spec.radius, spec.height));
      break;
    case PrimitiveType::Cone: {
      const double r = std::max(spec.radius, spec.radius2);
      b.add(Vec3(-r, -r, 0.0));
      b.add(Vec3(r, r, spec.height));
      break;
    }
    case PrimitiveType::Sphere:
      b.add(Vec3::Constant(-spec.radius));
      b.add(Vec3::Constant(spec.radius));
      break;
    case PrimitiveType::Torus: {
      const double r = spec.radius + spec.radius2;
      b.add(Vec3(-r, -r, -spec.radius2));
      b.add(Vec3(r, r, spec.radius2));
      break;
    }
    case PrimitiveType::Extrusion:
      for (const Vec2& q : spec.profile) {
        b.add(Vec3(q.x(), q.y(), 0.0));
        b.add(Vec3(q.x(), q.y(), spec.height));
      }
      break;
    case PrimitiveType::Revolution: {
      double rho_max = 0.0;
      for (const Vec2& q : spec.profile) {
        rho_max = std::max(rho_max, q.x());
        b.add(Vec3(0.0, 0.0, q.y()));
      }
      b.add(Vec3(-rho_max, -rho_max, b.min.z()));
      b.add(Vec3(rho_max, rho_max, b.max.z()));
      p.partial_turn = spec.angle < kTwoPi * (1.0 - 1e-15);
      break;
    }
  }
  p.local_center = 0.5 * (b.min + b.max);
  p.slack = 1e-10 * (b.max - b.min).norm();
  for (int corner = 0; corner < 8; ++corner) {
    const Vec3 q((corner & 1) ? b.max.x() : b.min.x(), (corner & 2) ? b.max.y() : b.min.y(),
                 (corner & 4) ? b.max.z() : b.min.z());
    p.world_bounds.add(spec.placement.apply_point(q));
  }
  // Rounding in the placement must not cut off a grazing hit.
  p.world_bounds.enlarge(1e-9 * (p.world_bounds.max - p.world_bounds.min).norm());
  return p;
}

std::optional<RayHit> hit_primitive(const PreparedPrimitive& p, const Vec3& origin,
                                    const Vec3& direction, double t_min, double t_max) {
  // Local ray: with the inverse similarity, local length = world length / scale.
  const Vec3 local_origin = p.rotation_transposed * (origin - p.translation) / p.scale;
  const Vec3 u = p.rotation_transposed * direction;
  const double shift = (p.local_center - local_origin).dot(u);
  const Vec3 o = local_origin + shift * u;
  Nearest best{t_min / p.scale - shift, t_max / p.scale - shift};
  const kernel::PrimitiveSpec& s = p.spec;
  const TurnLimit full_turn;
  switch (s.type) {
    case PrimitiveType::Box:
      hit_box(o, u, s.size, p.slack, best);
      break;
    case PrimitiveType::Cylinder:
    case PrimitiveType::Cone: {
      const double r2 = s.type == PrimitiveType::Cone ? s.radius2 : s.radius;
      const double k = (r2 - s.radius) / s.height;
      offer_quadric_side(o, u, s.radius, k, 0.0, s.height, p.slack, full_turn, best);
      if (s.radius > 0.0) offer_annulus(o, u, 0.0, 0.0, s.radius, p.slack, full_turn, best);
      if (r2 > 0.0) offer_annulus(o, u, s.height, 0.0, r2, p.slack, full_turn, best);
      break;
    }
    case PrimitiveType::Sphere:
      hit_sphere(o, u, s.radius, best);
      break;
    case PrimitiveType::Torus:
      hit_torus(o, u, s.radius, s.radius2, best);
      break;
    case PrimitiveType::Extrusion:
      hit_extrusion(p, o, u, best);
      break;
    case PrimitiveType::Revolution:
      hit_revolution(p, o, u, best);
      break;
  }
  if (best.s == kInf) return std::nullopt;
  RayHit hit;
  hit.t = (shift + best.s) * p.scale;
  Vec3 normal = (p.rotation_transposed.transpose() * best.normal).normalized();
  if (normal.dot(direction) > 0.0) normal = -normal;
  hit.normal = normal;
  hit.primitive = 0;
  return hit;
}

bool primitive_contains(const PreparedPrimitive& p, const Vec3& point) {
  const Vec3 q = p.rotation_transposed * (point - p.translation) / p.scale;
  const kernel::PrimitiveSpec& s = p.spec;
  for (const auto& c : s.clips) {
    if (c.head<3>().dot(q) > c.w()) return false;
  }
  switch (s.type) {
    case PrimitiveType::Box:
      return (q.array() >= 0.0).all() && (q.array() <= s.size.array()).all();
    case PrimitiveType::Cylinder:
    case PrimitiveType::Cone: {
      if (q.z() < 0.0 || q.z() > s.height) return false;
      const double r2 = s.type == PrimitiveType::Cone ? s.radius2 : s.radius;
      const double r = s.radius + (r2 - s.radius) * q.z() / s.height;
      return q.x() * q.x() + q.y() * q.y() <= r * r;
    }
    case PrimitiveType::Sphere:
      return q.squaredNorm() <= s.radius * s.radius;
    case PrimitiveType::Torus:
      return torus_distance(q, s.radius, s.radius2, nullptr) <= 0.0;
    case PrimitiveType::Extrusion:
      return q.z() >= 0.0 && q.z() <= s.height && inside_rings(p, Vec2(q.x(), q.y()));
    case PrimitiveType::Revolution: {
      TurnLimit turn;
      turn.angle = p.partial_turn ? s.angle : kTwoPi;
      return turn.contains(q) && inside_rings(p, Vec2(std::hypot(q.x(), q.y()), q.z()));
    }
  }
  return false;
}

}  // namespace csgtile::geo::detail
