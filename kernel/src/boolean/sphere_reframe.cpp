// The Boolean engine: full spheres given the (u, v) frame their sections need.

#include "boolean/engine.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <numbers>
#include <numeric>
#include <set>
#include <string>
#include "boolean/classifier.h"
#include "boolean/model.h"
#include "boolean/tolerance.h"
#include "csgtile/kernel/explorer.h"

namespace csgtile::kernel::detail {

namespace {

// A whole sphere as the builder makes it: one loop of its two poles (degenerate edges) and
// its seam used both ways. A cap cut from a sphere also has one loop of four uses (its rim,
// the seam twice, one pole) but is not whole: its rim must stay.
bool is_full_sphere(const BFace& face, const BModel& model) {
  if (face.surface->kind() != SurfaceKind::Sphere || face.loops.size() != 1 ||
      face.loops[0].size() != 4)
    return false;
  int poles = 0;
  for (const BUse& u : face.loops[0]) {
    if (model.edges[static_cast<std::size_t>(u.edge)].degenerate()) ++poles;
  }
  return poles == 2;
}

}  // namespace

void BooleanEngine::reframe_spheres() {
  const double tol = options_.tolerance;
  for (std::size_t f = 0; f < model_.faces.size(); ++f) {
    BFace& face = model_.faces[f];
    if (!is_full_sphere(face, model_)) continue;
    const auto& sphere = static_cast<const SphereSurface&>(*face.surface);
    const Vec3 center = sphere.frame().origin;
    const double r = sphere.radius();
    // Constraints from the overlapping faces of the other operand.
    std::vector<Vec3> axes;  // must be the sphere's axis (sphere centres, revolution axes)
    std::vector<std::pair<Vec3, bool>> planes;  // normal, passes through the centre
    bool impossible = false;
    const std::size_t lo = face.operand == 0 ? first_b_face_ : 0;
    const std::size_t hi = face.operand == 0 ? model_.faces.size() : first_b_face_;
    BoundingBox box = face.box;
    box.enlarge(tol);
    for (std::size_t g = lo; g < hi; ++g) {
      if (!box.intersects(model_.faces[g].box)) continue;
      const Surface& other = *model_.faces[g].surface;
      switch (other.kind()) {
        case SurfaceKind::Plane: {
          const Frame& pf = static_cast<const PlaneSurface&>(other).frame();
          const double distance = std::abs((center - pf.origin).dot(pf.z));
          if (distance >= r - tol) break;  // misses the sphere or touches it at a point
          planes.emplace_back(pf.z, distance <= tol);
          break;
        }
        case SurfaceKind::Sphere: {
          const Vec3 d = static_cast<const SphereSurface&>(other).frame().origin - center;
          if (d.norm() > tol) axes.push_back(d.normalized());
          break;
        }
        case SurfaceKind::Cylinder:
        case SurfaceKind::Cone:
        case SurfaceKind::Torus: {
          const Frame& of = other.kind() == SurfaceKind::Cylinder
                                ? static_cast<const CylinderSurface&>(other).frame()
                            : other.kind() == SurfaceKind::Cone
                                ? static_cast<const ConeSurface&>(other).frame()
                                : static_cast<const TorusSurface&>(other).frame();
          const Vec3 w = center - of.origin;
          if ((w - w.dot(of.z) * of.z).norm() > tol) impossible = true;
          axes.push_back(of.z);
          break;
        }
        default:
          impossible = true;
      }
    }
    if (impossible) {
      reframe_for_tracing(face, lo, hi);
      continue;
    }
    // Directions compared over the sphere (the tolerance model of the section code).
    const ToleranceModel across{tol, std::max(2.0 * r, tol)};
    auto compatible = [&](const Vec3& z) {
      for (const Vec3& a : axes) {
        if (!across.parallel(a, z)) return false;
      }
      for (const auto& [n, through_center] : planes) {
        const bool latitude = across.parallel(n, z);
        const bool meridian = through_center && across.perpendicular(n, z);
        if (!latitude && !meridian) return false;
      }
      return true;
    };
    std::vector<Vec3> candidates{sphere.frame().z};
    for (const Vec3& a : axes) candidates.push_back(a);
    for (const auto& pl : planes) candidates.push_back(pl.first);
    std::optional<Vec3> z;
    for (const Vec3& c : candidates) {
      if (compatible(c.normalized())) {
        z = c.normalized();
        break;
      }
    }
    if (!z) {
      reframe_for_tracing(face, lo, hi);
      continue;
    }
    // Seam direction: away from every meridian plane.
    const Frame base = Frame::from_z(center, *z, sphere.frame().x);
    double best_angle = 0, best_score = -1;
    for (int k = 0; k < 16; ++k) {
      const double phi = 0.3 + k * 0.39;  // not a simple fraction of π
      const Vec3 x = std::cos(phi) * base.x + std::sin(phi) * base.y;
      double score = 1.0;
      for (const auto& [n, through_center] : planes) {
        if (through_center && across.perpendicular(n, *z))
          score = std::min(score, std::abs(x.dot(n)));
      }
      if (score > best_score + kSeamPreference) {
        best_score = score;
        best_angle = phi;
      }
    }
    Frame frame;
    frame.origin = center;
    frame.z = *z;
    frame.x = std::cos(best_angle) * base.x + std::sin(best_angle) * base.y;
    frame.y = frame.z.cross(frame.x);
    rebuild_full_sphere(face, frame, r);
  }
}

void BooleanEngine::reframe_for_tracing(BFace& face, std::size_t lo, std::size_t hi) {
  const auto& sphere = static_cast<const SphereSurface&>(*face.surface);
  const Vec3 center = sphere.frame().origin;
  const double r = sphere.radius();
  BoundingBox box = face.box;
  box.enlarge(options_.tolerance);
  auto box_distance = [](const BoundingBox& b, const Vec3& p) {
    return (p - p.cwiseMax(b.min).cwiseMin(b.max)).norm();
  };
  const Vec3 directions[] = {{0, 0, 1},  {1, 0, 0},  {0, 1, 0}, {1, 1, 1},  {1, -1, 1},
                             {-1, 1, 1}, {1, 1, -1}, {1, 1, 0}, {1, -1, 0}, {1, 0, 1},
                             {1, 0, -1}, {0, 1, 1},  {0, 1, -1}};
  std::vector<Vec3> candidates{sphere.frame().z};  // the current frame wins ties
  for (const Vec3& d : directions) candidates.push_back(d.normalized());
  Vec3 best = sphere.frame().z;
  double best_score = -1.0;
  for (const Vec3& z : candidates) {
    double score = std::numeric_limits<double>::infinity();
    for (const Vec3& pole : {Vec3(center + r * z), Vec3(center - r * z)}) {
      for (std::size_t g = lo; g < hi; ++g) {
        if (!box.intersects(model_.faces[g].box)) continue;
        score = std::min(score, box_distance(model_.faces[g].box, pole));
      }
    }
    if (score > best_score) {
      best_score = score;
      best = z;
    }
  }
  rebuild_full_sphere(face, Frame::from_z(center, best, sphere.frame().x), r);
}

void BooleanEngine::rebuild_full_sphere(BFace& face, const Frame& frame, double r) {
  constexpr double kHalfPi = std::numbers::pi / 2, kTwoPi = 2 * std::numbers::pi;
  face.surface = std::make_shared<SphereSurface>(frame, r);
  const int south = model_.vertex_at(frame.origin - r * frame.z);
  const int north = model_.vertex_at(frame.origin + r * frame.z);
  Frame meridian;
  meridian.origin = frame.origin;
  meridian.x = frame.x;
  meridian.y = frame.z;
  meridian.z = meridian.x.cross(meridian.y);
  BEdge seam;
  seam.curve = std::make_shared<CircleCurve>(meridian, r);
  seam.t0 = -kHalfPi;
  seam.t1 = kHalfPi;
  seam.v0 = south;
  seam.v1 = north;
  seam.tolerance = options_.tolerance;
  seam.seam = true;
  BEdge pole_s, pole_n;
  pole_s.t0 = pole_n.t0 = 0;
  pole_s.t1 = pole_n.t1 = kTwoPi;
  pole_s.v0 = pole_s.v1 = south;
  pole_n.v0 = pole_n.v1 = north;
  pole_s.tolerance = pole_n.tolerance = options_.tolerance;
  const int es = model_.add_edge(seam), ps = model_.add_edge(pole_s), pn = model_.add_edge(pole_n);
  face.loops = {{{ps, true, std::make_shared<Line2d>(Vec2(0, -kHalfPi), Vec2(1, 0))},
                 {es, true, std::make_shared<Line2d>(Vec2(kTwoPi, 0), Vec2(0, 1))},
                 {pn, false, std::make_shared<Line2d>(Vec2(0, kHalfPi), Vec2(1, 0))},
                 {es, false, std::make_shared<Line2d>(Vec2(0, 0), Vec2(0, 1))}}};
}

}  // namespace csgtile::kernel::detail
