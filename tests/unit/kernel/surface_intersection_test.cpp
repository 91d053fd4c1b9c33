// Closed-form surface–surface intersection (boolean/surface_intersection.h): for every
// supported pair, in a canonical placement and under seeded random similarities, the number
// of curves, their closed and tangent flags, points on both surfaces, and the
// parametrisation contract (the curve parameter is the surfaces' own angle or length);
// coincident and unsupported pairs; clipping.

#include "boolean/surface_intersection.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <memory>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "random_shapes.h"

namespace csgtile::kernel::detail {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kTwoPi = 2.0 * std::numbers::pi;
/// World tolerance per unit of scale, and the accuracy required of section points.
constexpr double kTolerance = 1e-7;
constexpr double kAccuracy = 1e-9;
constexpr int kPlacements = 8;

// ---- Surfaces in a local placement --------------------------------------------------------

SurfacePtr plane(const Vec3& origin, const Vec3& normal, const Vec3& x_hint = Vec3::UnitX()) {
  return std::make_shared<PlaneSurface>(Frame::from_z(origin, normal, x_hint));
}
SurfacePtr cylinder(const Vec3& origin, const Vec3& axis, double r,
                    const Vec3& x_hint = Vec3::UnitX()) {
  return std::make_shared<CylinderSurface>(Frame::from_z(origin, axis, x_hint), r);
}
SurfacePtr cone(const Vec3& origin, const Vec3& axis, double r, double semi_angle) {
  return std::make_shared<ConeSurface>(Frame::from_z(origin, axis), r, semi_angle);
}
SurfacePtr sphere(const Vec3& origin, double r, const Vec3& axis = Vec3::UnitZ()) {
  return std::make_shared<SphereSurface>(Frame::from_z(origin, axis), r);
}
SurfacePtr torus(const Vec3& origin, const Vec3& axis, double big, double small) {
  return std::make_shared<TorusSurface>(Frame::from_z(origin, axis), big, small);
}

/// The cone used by the plane–cone scenes: radius 1 at z = 0, apex at (0, 0, 2).
const double kConeAngle = -std::atan2(1.0, 2.0);
SurfacePtr narrowing_cone() { return cone(Vec3::Zero(), Vec3::UnitZ(), 1.0, kConeAngle); }

// ---- Placement and checks -----------------------------------------------------------------

/// A pair of surfaces and a clip box moved together by a similarity.
struct Placed {
  SurfacePtr a, b;
  BoundingBox clip;
  double scale = 1.0;
  double tolerance = kTolerance;
  double size = 1.0;  // the clip box diagonal
};

Placed place(const SurfacePtr& a, const SurfacePtr& b, double extent, const Location& loc) {
  Placed p;
  p.a = a->transformed(loc);
  p.b = b->transformed(loc);
  for (int i = 0; i < 8; ++i) {
    const Vec3 corner((i & 1) ? extent : -extent, (i & 2) ? extent : -extent,
                      (i & 4) ? extent : -extent);
    p.clip.add(loc.apply_point(corner));
  }
  p.scale = loc.scale();
  p.tolerance = kTolerance * loc.scale();
  p.size = p.clip.size().norm();
  return p;
}

SsiResult run(const Placed& p) { return intersect_surfaces(*p.a, *p.b, p.clip, p.tolerance); }

double distance_to(const Surface& s, const Vec3& p) {
  const Vec2 uv = s.closest_parameters(p);
  return (s.point(uv.x(), uv.y()) - p).norm();
}

/// Samples along a curve's range (both ends included).
std::vector<double> samples(const SectionCurve& c, int count = 24) {
  std::vector<double> t;
  for (int k = 0; k <= count; ++k) t.push_back(c.first + (c.last - c.first) * k / count);
  return t;
}

void expect_on_both(const SsiResult& r, const Placed& p) {
  for (const SectionCurve& c : r.curves) {
    ASSERT_TRUE(c.curve);
    EXPECT_LT(c.first, c.last);
    for (double t : samples(c)) {
      const Vec3 q = c.curve->point(t);
      EXPECT_LE(distance_to(*p.a, q), kAccuracy * p.size) << "t = " << t;
      EXPECT_LE(distance_to(*p.b, q), kAccuracy * p.size) << "t = " << t;
    }
  }
}

/// |a − b| modulo 2π.
double angle_gap(double a, double b) {
  const double d = std::fmod(std::abs(a - b), kTwoPi);
  return std::min(d, kTwoPi - d);
}

std::vector<Location> placements(std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::vector<Location> out{Location()};
  for (int i = 0; i < kPlacements; ++i) out.push_back(test::random_similarity(rng));
  return out;
}

// ---- Scenes -------------------------------------------------------------------------------

struct Scene {
  std::string name;
  SurfacePtr a, b;
  SsiKind kind = SsiKind::Curves;
  int curves = 0;
  int closed = 0;
  int tangent = 0;
  double extent = 4.0;  // half-size of the local clip cube
  bool traced = false;  // no closed form: traced polylines (curves = how many, -1: any ≥ 1)
};

constexpr int kAnyCount = -1;

// A traced section: polylines with pcurves on both surfaces, every vertex on both surfaces
// (at its stored parameters too), every point of the chords within the reported deviation,
// which is within the tracer's chordal bound max(10·tolerance, 1e-6·size).
void expect_traced(const SsiResult& r, const Placed& p, int curves) {
  if (curves == kAnyCount) {
    EXPECT_GE(r.curves.size(), 1u);
  } else {
    EXPECT_EQ(static_cast<int>(r.curves.size()), curves);
  }
  const double size = std::max(p.clip.size().norm(), p.tolerance);
  const double bound = std::max(10 * p.tolerance, 1e-6 * size) * (1 + 1e-9);
  for (const SectionCurve& c : r.curves) {
    ASSERT_EQ(c.curve->kind(), CurveKind::Polyline);
    ASSERT_TRUE(c.pcurve_a && c.pcurve_b);
    EXPECT_LE(c.deviation, bound);
    const auto& points = static_cast<const PolylineCurve&>(*c.curve).points();
    for (std::size_t i = 0; i < points.size(); ++i) {
      EXPECT_LE(distance_to(*p.a, points[i]), 1e-9 * size);
      EXPECT_LE(distance_to(*p.b, points[i]), 1e-9 * size);
      const Vec2 ua = c.pcurve_a->point(static_cast<double>(i));
      const Vec2 ub = c.pcurve_b->point(static_cast<double>(i));
      EXPECT_LE((p.a->point(ua.x(), ua.y()) - points[i]).norm(), 1e-9 * size);
      EXPECT_LE((p.b->point(ub.x(), ub.y()) - points[i]).norm(), 1e-9 * size);
    }
    for (std::size_t i = 0; i + 1 < points.size(); ++i) {
      const Vec3 mid = 0.5 * (points[i] + points[i + 1]);
      EXPECT_LE(distance_to(*p.a, mid), c.deviation * 1.01);
      EXPECT_LE(distance_to(*p.b, mid), c.deviation * 1.01);
    }
  }
}

void check_scene(const Scene& s, std::uint64_t seed) {
  for (const Location& loc : placements(seed)) {
    for (const bool swapped : {false, true}) {
      SCOPED_TRACE(s.name + (swapped ? " (swapped)" : "") + ", scale " +
                   std::to_string(loc.scale()));
      const Placed p = swapped ? place(s.b, s.a, s.extent, loc) : place(s.a, s.b, s.extent, loc);
      const SsiResult r = run(p);
      ASSERT_EQ(r.kind, s.kind) << r.reason;
      if (s.traced) {
        expect_traced(r, p, s.curves);
        continue;
      }
      if (s.kind == SsiKind::Unsupported) {
        EXPECT_FALSE(r.reason.empty());
        EXPECT_TRUE(r.curves.empty());
        continue;
      }
      ASSERT_EQ(static_cast<int>(r.curves.size()), s.curves);
      const auto closed = std::count_if(r.curves.begin(), r.curves.end(),
                                        [](const SectionCurve& c) { return c.closed; });
      const auto tangent = std::count_if(r.curves.begin(), r.curves.end(),
                                         [](const SectionCurve& c) { return c.tangent; });
      EXPECT_EQ(closed, s.closed);
      EXPECT_EQ(tangent, s.tangent);
      for (const SectionCurve& c : r.curves) {
        if (c.closed) {
          EXPECT_EQ(c.curve->kind(), CurveKind::Trig);
          EXPECT_EQ(c.first, 0.0);
          EXPECT_EQ(c.last, kTwoPi);
        } else {
          EXPECT_EQ(c.curve->kind(), CurveKind::Line);
        }
      }
      expect_on_both(r, p);
    }
  }
}

void check_scenes(const std::vector<Scene>& scenes, std::uint64_t seed) {
  for (const Scene& s : scenes) check_scene(s, seed++);
}

const Vec3 kX = Vec3::UnitX(), kY = Vec3::UnitY(), kZ = Vec3::UnitZ(), kO = Vec3::Zero();

TEST(SurfaceIntersection, PlanePlane) {
  check_scenes(
      {{"oblique", plane(kO, kZ), plane(Vec3(1, 0, 0), Vec3(1, 0, 1)), SsiKind::Curves, 1, 0, 0},
       {"perpendicular", plane(kO, kZ), plane(kO, kY), SsiKind::Curves, 1, 0, 0},
       {"parallel", plane(kO, kZ), plane(Vec3(0, 0, 1), kZ), SsiKind::Curves, 0},
       {"coincident, flipped", plane(kO, kZ), plane(Vec3(3, -1, 0), -kZ, kY), SsiKind::Coincident}},
      101);
}

TEST(SurfaceIntersection, PlaneCylinder) {
  const SurfacePtr c = cylinder(kO, kZ, 1.0);
  check_scenes(
      {{"perpendicular: circle", plane(Vec3(0, 0, 0.3), kZ), c, SsiKind::Curves, 1, 1},
       {"oblique: ellipse", plane(Vec3(0, 0, 0.5), Vec3(0, 0.6, 0.8)), c, SsiKind::Curves, 1, 1},
       {"steep: ellipse", plane(kO, Vec3(1, 0, 0.3)), c, SsiKind::Curves, 1, 1, 0, 8.0},
       {"parallel, cutting: two lines", plane(Vec3(0.5, 0, 0), kX), c, SsiKind::Curves, 2, 0, 0},
       {"through the axis: two lines", plane(kO, Vec3(1, 1, 0)), c, SsiKind::Curves, 2},
       {"parallel, tangent: one line", plane(Vec3(1, 0, 0), kX), c, SsiKind::Curves, 1, 0, 1},
       {"parallel, tangent from inside normal", plane(Vec3(0, -1, 0), -kY), c, SsiKind::Curves, 1,
        0, 1},
       {"parallel, apart", plane(Vec3(1.5, 0, 0), kX), c, SsiKind::Curves, 0}},
      201);
}

TEST(SurfaceIntersection, PlaneCone) {
  const SurfacePtr k = narrowing_cone();
  check_scenes(
      {{"perpendicular: circle", plane(Vec3(0, 0, 1), kZ), k, SsiKind::Curves, 1, 1},
       {"perpendicular beyond the apex", plane(Vec3(0, 0, 3), kZ), k, SsiKind::Curves, 0},
       {"perpendicular at the apex", plane(Vec3(0, 0, 2), -kZ), k, SsiKind::Curves, 0},
       {"through the axis: two generatrices", plane(kO, kX), k, SsiKind::Curves, 2, 0, 0},
       {"through the apex, oblique: two generatrices", plane(Vec3(0, 0, 2), Vec3(1, 0, 0.2)), k,
        SsiKind::Curves, 2, 0, 0},
       {"tangent along a generatrix", plane(Vec3(1, 0, 0), Vec3(2, 0, 1)), k, SsiKind::Curves, 1, 0,
        1},
       {"through the apex only", plane(Vec3(0, 0, 2), Vec3(0.2, 0, 1)), k, SsiKind::Curves, 0},
       {"beyond the apex, tilted", plane(Vec3(0, 0, 2.5), Vec3(0.1, 0, 1)), k, SsiKind::Curves, 0},
       {"oblique conic", plane(Vec3(0, 0, 0.5), Vec3(0.3, 0, 1)), k, SsiKind::Curves, kAnyCount, 0,
        0, 4.0, true}},
      301);
}

TEST(SurfaceIntersection, PlaneSphere) {
  const SurfacePtr s = sphere(kO, 1.0);
  check_scenes(
      {{"cutting: circle", plane(Vec3(0, 0, 0.5), kZ), s, SsiKind::Curves, 1, 1},
       {"oblique: circle", plane(Vec3(0.2, 0.2, 0.2), Vec3(1, 1, 1)), s, SsiKind::Curves, 1, 1},
       {"through the axis: great circle", plane(kO, Vec3(1, 2, 0)), s, SsiKind::Curves, 1, 1},
       {"tangent: a point", plane(Vec3(0, 0, 1), kZ), s, SsiKind::Curves, 0},
       {"tangent obliquely: a point", plane(Vec3(1, 1, 1) / std::sqrt(3.0), Vec3(1, 1, 1)), s,
        SsiKind::Curves, 0},
       {"apart", plane(Vec3(0, 0, 2), Vec3(0.1, 0, 1)), s, SsiKind::Curves, 0}},
      401);
}

TEST(SurfaceIntersection, PlaneTorus) {
  const SurfacePtr t = torus(kO, kZ, 2.0, 0.5);
  check_scenes(
      {{"equator: two circles", plane(kO, kZ), t, SsiKind::Curves, 2, 2},
       {"low: two circles", plane(Vec3(0, 0, -0.25), -kZ), t, SsiKind::Curves, 2, 2},
       {"top: tangent circle", plane(Vec3(0, 0, 0.5), kZ), t, SsiKind::Curves, 1, 1, 1},
       {"above", plane(Vec3(0, 0, 0.6), kZ), t, SsiKind::Curves, 0},
       {"through the axis: two meridians", plane(kO, Vec3(1, 2, 0)), t, SsiKind::Curves, 2, 2},
       {"parallel to the axis, apart", plane(Vec3(3, 0, 0), kX), t, SsiKind::Curves, 0},
       {"tilted, apart", plane(Vec3(0, 0, 1.5), Vec3(0.3, 0, 1)), t, SsiKind::Curves, 0},
       {"parallel to the axis: spiric", plane(Vec3(1, 0, 0), kX), t, SsiKind::Curves, kAnyCount, 0,
        0, 4.0, true},
       {"oblique", plane(kO, Vec3(0.1, 0, 1)), t, SsiKind::Curves, 2, 0, 0, 4.0, true}},
      501);
}

TEST(SurfaceIntersection, CylinderCylinder) {
  const SurfacePtr c = cylinder(kO, kZ, 1.0);
  check_scenes(
      {{"parallel, crossing: two lines", c, cylinder(Vec3(1, 0, 0), kZ, 1.0), SsiKind::Curves, 2, 0,
        0},
       {"parallel, opposite axes: two lines", c, cylinder(Vec3(0.5, 1, 0), -kZ, 0.7),
        SsiKind::Curves, 2, 0, 0},
       {"external tangent", c, cylinder(Vec3(0, 2, 0), kZ, 1.0), SsiKind::Curves, 1, 0, 1},
       {"internal tangent", c, cylinder(Vec3(0.5, 0, 0), -kZ, 0.5), SsiKind::Curves, 1, 0, 1},
       {"nested", c, cylinder(Vec3(0.2, 0, 0), kZ, 0.3), SsiKind::Curves, 0},
       {"apart", c, cylinder(Vec3(3, 0, 0), kZ, 1.0), SsiKind::Curves, 0},
       {"coaxial, different radii", c, cylinder(Vec3(0, 0, 5), -kZ, 0.5), SsiKind::Curves, 0},
       {"coincident", c, cylinder(Vec3(0, 0, 2), -kZ, 1.0, kY), SsiKind::Coincident},
       {"Steinmetz, perpendicular", c, cylinder(kO, kX, 1.0), SsiKind::Curves, 2, 2, 0},
       {"Steinmetz, 60 degrees", c, cylinder(Vec3(0, 0, 1), Vec3(0, std::sqrt(3.0), 1), 1.0),
        SsiKind::Curves, 2, 2, 0, 6.0},
       {"skew", c, cylinder(Vec3(0, 0.5, 0), kX, 1.0), SsiKind::Curves, kAnyCount, 0, 0, 4.0, true},
       {"crossing, different radii", c, cylinder(kO, kX, 0.5), SsiKind::Curves, 2, 0, 0, 4.0, true},
       {"skew, apart", c, cylinder(Vec3(0, 3, 0), kX, 1.0), SsiKind::Curves, 0},
       {"skew, touching at a point", c, cylinder(Vec3(0, 1.5, 0), kX, 0.5), SsiKind::Curves, 0}},
      601);
}

TEST(SurfaceIntersection, Coaxial) {
  const SurfacePtr c = cylinder(kO, kZ, 0.6);
  check_scenes(
      {{"cylinder–sphere: two circles", c, sphere(kO, 1.0), SsiKind::Curves, 2, 2},
       {"cylinder–sphere with a tilted frame", c, sphere(Vec3(0, 0, 1), 1.0, Vec3(1, 1, 0)),
        SsiKind::Curves, 2, 2},
       {"cylinder–sphere, tangent", c, sphere(Vec3(0, 0, 2), 0.6), SsiKind::Curves, 1, 1, 1},
       {"cylinder–sphere, apart", c, sphere(kO, 0.5), SsiKind::Curves, 0},
       {"cylinder–cone", c, narrowing_cone(), SsiKind::Curves, 1, 1},
       {"cone–sphere", narrowing_cone(), sphere(kO, 1.0, Vec3(0, 1, 1)), SsiKind::Curves, 2, 2},
       {"cone–cone, opposite", narrowing_cone(), cone(Vec3(0, 0, 2), -kZ, 1.0, kConeAngle),
        SsiKind::Curves, 1, 1},
       {"cone–cone, translated", narrowing_cone(), cone(Vec3(0, 0, 4), kZ, 1.0, kConeAngle),
        SsiKind::Curves, 0},
       {"cone–cone, apex to apex", narrowing_cone(), cone(Vec3(0, 0, 4), -kZ, 1.0, kConeAngle),
        SsiKind::Curves, 0},
       {"cone–cone, coincident", narrowing_cone(), cone(Vec3(0, 0, 1), kZ, 0.5, kConeAngle),
        SsiKind::Coincident},
       {"cylinder–torus, outer tangent", cylinder(kO, -kZ, 2.5), torus(kO, kZ, 2.0, 0.5),
        SsiKind::Curves, 1, 1, 1},
       {"cylinder–torus, inner tangent", cylinder(kO, kZ, 1.5), torus(kO, kZ, 2.0, 0.5),
        SsiKind::Curves, 1, 1, 1},
       {"cylinder–torus, through the tube", cylinder(kO, kZ, 2.0), torus(kO, kZ, 2.0, 0.5),
        SsiKind::Curves, 2, 2},
       {"cylinder–torus, in the hole", cylinder(kO, kZ, 1.0), torus(kO, kZ, 2.0, 0.5),
        SsiKind::Curves, 0},
       {"torus–sphere", torus(kO, kZ, 2.0, 0.5), sphere(kO, 2.0), SsiKind::Curves, 2, 2},
       {"torus–sphere, shifted", torus(kO, kZ, 2.0, 0.5), sphere(Vec3(0, 0, 1), 2.0),
        SsiKind::Curves, 2, 2},
       {"torus–torus", torus(kO, kZ, 2.0, 0.5), torus(Vec3(0, 0, 0.5), -kZ, 2.0, 0.5),
        SsiKind::Curves, 2, 2},
       {"torus–torus, tangent", torus(kO, kZ, 2.0, 0.5), torus(Vec3(0, 0, 1), kZ, 2.0, 0.5),
        SsiKind::Curves, 1, 1, 1},
       {"torus–torus, coincident", torus(kO, kZ, 2.0, 0.5), torus(kO, -kZ, 2.0, 0.5),
        SsiKind::Coincident},
       {"torus–cone", torus(kO, kZ, 2.0, 0.5), cone(Vec3(0, 0, 0), kZ, 2.0, 0.3), SsiKind::Curves,
        2, 2}},
      701);
}

TEST(SurfaceIntersection, SphereSphere) {
  const SurfacePtr s = sphere(kO, 1.0);
  check_scenes(
      {{"overlapping: one circle", s, sphere(Vec3(1.2, 0, 0), 0.8), SsiKind::Curves, 1, 1},
       {"overlapping, aligned frames", s, sphere(Vec3(0, 0, 1.2), 0.8), SsiKind::Curves, 1, 1},
       {"overlapping, random frames", sphere(kO, 1.0, Vec3(1, 2, 3)),
        sphere(Vec3(0.3, -0.7, 0.5), 0.6, Vec3(-1, 0, 1)), SsiKind::Curves, 1, 1},
       {"touching outside: a point", s, sphere(Vec3(1.8, 0, 0), 0.8), SsiKind::Curves, 0},
       {"touching inside: a point", s, sphere(Vec3(0, 0.5, 0), 0.5), SsiKind::Curves, 0},
       {"apart", s, sphere(Vec3(3, 0, 0), 1.0), SsiKind::Curves, 0},
       {"nested", s, sphere(Vec3(0.1, 0, 0), 0.5), SsiKind::Curves, 0},
       {"concentric", s, sphere(kO, 0.5), SsiKind::Curves, 0},
       {"coincident", s, sphere(kO, 1.0, kX), SsiKind::Coincident}},
      801);
}

TEST(SurfaceIntersection, OffAxisPairs) {
  check_scenes(
      {// The sphere's poles lie on the cylinder: its pcurve would have to jump there.
       {"cylinder–sphere through the poles", cylinder(kO, kZ, 1.0), sphere(Vec3(1, 0, 0), 0.5),
        SsiKind::Unsupported},
       {"cylinder–sphere off the axis", cylinder(kO, kZ, 1.0), sphere(Vec3(1.2, 0, 0), 0.5),
        SsiKind::Curves, 1, 0, 0, 4.0, true},
       {"cylinder–sphere, apart", cylinder(kO, kZ, 1.0), sphere(Vec3(3, 0, 0), 0.5),
        SsiKind::Curves, 0},
       {"cylinder–sphere, ball inside", cylinder(kO, kZ, 1.0), sphere(Vec3(0.3, 0, 0), 0.5),
        SsiKind::Curves, 0},
       {"sphere–torus off the axis", sphere(Vec3(2, 0, 0), 0.7), torus(kO, kZ, 2.0, 0.5),
        SsiKind::Curves, kAnyCount, 0, 0, 4.0, true},
       {"sphere–torus, ball inside the tube", sphere(Vec3(2, 0, 0.1), 0.2), torus(kO, kZ, 2.0, 0.5),
        SsiKind::Curves, 0},
       {"sphere–torus, torus inside the ball", sphere(Vec3(0.5, 0, 0), 3.5),
        torus(kO, kZ, 2.0, 0.5), SsiKind::Curves, 0, 0, 0, 6.0},
       {"cone–cylinder, skew", narrowing_cone(), cylinder(Vec3(0, 0, 1), kX, 0.5), SsiKind::Curves,
        kAnyCount, 0, 0, 4.0, true},
       {"torus–torus, linked (tubes apart)", torus(kO, kZ, 2.0, 0.5),
        torus(Vec3(2, 0, 0), kY, 2.0, 0.5), SsiKind::Curves, 0, 0, 0, 4.0, true},
       {"torus–torus, tubes crossing", torus(kO, kZ, 2.0, 0.5), torus(Vec3(2, 0, 0), kY, 0.6, 0.3),
        SsiKind::Curves, kAnyCount, 0, 0, 4.0, true}},
      901);
}

TEST(SurfaceIntersection, SurfacesWithoutClosedFormsAreTracedOrNamed) {
  const SurfacePtr p = plane(kO, kZ);
  const SurfacePtr extrusion = std::make_shared<ExtrusionSurface>(
      std::make_shared<CircleCurve>(Frame(), 1.0), Vec3::UnitZ());
  const SurfacePtr revolution = std::make_shared<RevolutionSurface>(
      std::make_shared<LineCurve>(Vec3(1, 0, 0), Vec3(1, 0, 1)), kO, kZ);
  BoundingBox clip;
  clip.add(Vec3(-2, -2, -2));
  clip.add(Vec3(2, 2, 2));
  Placed placed;
  placed.clip = clip;
  // An extrusion of a circle cut by a plane across it: one traced loop.
  placed.a = p;
  placed.b = extrusion;
  const SsiResult e = intersect_surfaces(*p, *extrusion, clip, kTolerance);
  ASSERT_EQ(e.kind, SsiKind::Curves) << e.reason;
  expect_traced(e, placed, 1);
  // A revolved line (a cone) against a sphere: traced.
  placed.a = revolution;
  placed.b = sphere(kO, 1.5);
  const SsiResult r = intersect_surfaces(*placed.a, *placed.b, clip, kTolerance);
  ASSERT_EQ(r.kind, SsiKind::Curves) << r.reason;
  expect_traced(r, placed, kAnyCount);
  // The same extrusion twice: they coincide, which tracing cannot follow: a named refusal.
  const SsiResult k = intersect_surfaces(*extrusion, *extrusion, clip, kTolerance);
  EXPECT_EQ(k.kind, SsiKind::Unsupported);
  EXPECT_NE(k.reason.find("extrusion"), std::string::npos) << k.reason;
  EXPECT_NE(k.reason.find("tangent"), std::string::npos) << k.reason;
}

// ---- The parametrisation contract -------------------------------------------------------

/// Every closed curve of r is C(t) = S(t, ·) on s: the surface's angle u equals t.
void expect_angle_follows_t(const SsiResult& r, const Surface& s) {
  for (const SectionCurve& c : r.curves) {
    ASSERT_TRUE(c.closed);
    for (double t : samples(c)) {
      EXPECT_LE(angle_gap(s.closest_parameters(c.curve->point(t)).x(), t), 1e-9) << "t = " << t;
    }
  }
}

/// Every closed curve of r is C(t) = S(u0, t) on s: u constant, v equals t.
void expect_meridian(const SsiResult& r, const Surface& s) {
  for (const SectionCurve& c : r.curves) {
    ASSERT_TRUE(c.closed);
    const Vec3 start = c.curve->point(0.0);
    const double u0 = s.closest_parameters(start).x();
    for (double t : samples(c)) {
      const Vec3 expected = s.point(u0, t);
      EXPECT_LE((c.curve->point(t) - expected).norm(), kAccuracy * (1.0 + expected.norm()))
          << "t = " << t;
    }
  }
}

TEST(SurfaceIntersection, CirclesFollowTheAngleOfSurfaceA) {
  int seed = 1001;
  struct Pair {
    SurfacePtr a, b;
    int curves;
  };
  const std::vector<Pair> pairs = {
      {cylinder(kO, kZ, 0.6, Vec3(1, 1, 0)), sphere(kO, 1.0, Vec3(1, 0, 1)), 2},
      {sphere(kO, 1.0, kZ), cylinder(kO, -kZ, 0.6, kY), 2},
      {narrowing_cone(), torus(Vec3(0, 0, 0.5), -kZ, 1.0, 0.5), 2},
      {torus(kO, -kZ, 2.0, 0.5), cylinder(kO, kZ, 2.2), 2},
      {cylinder(kO, kZ, 1.0, kY), plane(Vec3(0, 0, 0.4), Vec3(0.3, -0.4, 1)), 1},  // ellipse
      {cylinder(kO, kZ, 1.0), cylinder(kO, Vec3(1, 1, 0.5), 1.0), 2},              // Steinmetz
  };
  for (const Pair& pair : pairs) {
    for (const Location& loc : placements(seed++)) {
      const Placed p = place(pair.a, pair.b, 4.0, loc);
      const SsiResult r = run(p);
      ASSERT_EQ(r.kind, SsiKind::Curves) << r.reason;
      ASSERT_EQ(static_cast<int>(r.curves.size()), pair.curves);
      expect_on_both(r, p);
      expect_angle_follows_t(r, *p.a);
    }
  }
}

TEST(SurfaceIntersection, PlaneSectionsFollowTheRevolutionSurface) {
  int seed = 1101;
  for (const Location& loc : placements(seed++)) {
    // Plane first: the circle still follows the cylinder's angle.
    const Placed p =
        place(plane(Vec3(0, 0, 0.2), Vec3(0.1, 0.2, 1)), cylinder(kO, kZ, 1.0, kY), 4.0, loc);
    const SsiResult r = run(p);
    ASSERT_EQ(r.curves.size(), 1u);
    expect_angle_follows_t(r, *p.b);
  }
  for (const Location& loc : placements(seed++)) {
    const Placed p = place(plane(Vec3(0, 0, 0.3), kZ), torus(kO, -kZ, 2.0, 0.5), 4.0, loc);
    const SsiResult r = run(p);
    ASSERT_EQ(r.curves.size(), 2u);
    expect_angle_follows_t(r, *p.b);
  }
  for (const Location& loc : placements(seed++)) {
    const Placed p = place(torus(kO, kZ, 2.0, 0.5), plane(kO, Vec3(2, -1, 0)), 4.0, loc);
    const SsiResult r = run(p);
    ASSERT_EQ(r.curves.size(), 2u);
    expect_meridian(r, *p.a);
    for (const SectionCurve& c : r.curves) {
      for (double t : samples(c)) {
        EXPECT_LE(angle_gap(p.a->closest_parameters(c.curve->point(t)).y(), t), 1e-9);
      }
    }
  }
  for (const Location& loc : placements(seed++)) {
    const Placed p = place(plane(kO, Vec3(1, 3, 0)), sphere(kO, 1.0, kZ), 4.0, loc);
    const SsiResult r = run(p);
    ASSERT_EQ(r.curves.size(), 1u);
    expect_meridian(r, *p.b);
  }
  for (const Location& loc : placements(seed++)) {
    // A parallel of the sphere: C(t) = S(t, v0).
    const Placed p = place(sphere(kO, 1.0, kZ), plane(Vec3(0, 0, -0.4), kZ), 4.0, loc);
    const SsiResult r = run(p);
    ASSERT_EQ(r.curves.size(), 1u);
    expect_angle_follows_t(r, *p.a);
  }
}

TEST(SurfaceIntersection, LinesFollowTheGeneratrixLength) {
  int seed = 1201;
  struct Pair {
    SurfacePtr a, b;
    int curves;
  };
  const std::vector<Pair> pairs = {
      {cylinder(kO, kZ, 1.0), plane(Vec3(0.3, 0, 0), Vec3(1, 1, 0)), 2},
      {cylinder(kO, kZ, 1.0), cylinder(Vec3(1, 0.5, 0), -kZ, 0.8), 2},
      {narrowing_cone(), plane(Vec3(0, 0, 2), Vec3(1, 0, 0.2)), 2},
      {narrowing_cone(), plane(kO, Vec3(1, 1, 0)), 2},
  };
  for (const Pair& pair : pairs) {
    for (const Location& loc : placements(seed++)) {
      const Placed p = place(pair.a, pair.b, 4.0, loc);
      const SsiResult r = run(p);
      ASSERT_EQ(static_cast<int>(r.curves.size()), pair.curves);
      expect_on_both(r, p);
      for (const SectionCurve& c : r.curves) {
        ASSERT_EQ(c.curve->kind(), CurveKind::Line);
        const double middle = 0.5 * (c.first + c.last);
        const Vec2 reference = p.a->closest_parameters(c.curve->point(middle));
        for (double t : samples(c)) {
          const Vec2 uv = p.a->closest_parameters(c.curve->point(t));
          // The angle is undefined at a cone's apex (ρ = |∂S/∂u| = 0).
          if (p.a->du(uv.x(), uv.y()).norm() > 1e-6 * p.scale) {
            EXPECT_LE(angle_gap(uv.x(), reference.x()), 1e-9);
          }
          // v is a length, scaled with the placement; the line's t is the world arc length.
          EXPECT_NEAR(uv.y() - reference.y(), t - middle, 1e-9 * p.size);
        }
      }
    }
  }
}

TEST(SurfaceIntersection, SteinmetzEllipsesSatisfyBothCylinders) {
  // The three cylinders of steinmetz3_common (r = 1, axes x, y, z through the origin).
  const std::array<Vec3, 3> axes = {kX, kY, kZ};
  for (const Location& loc : placements(1301)) {
    for (int i = 0; i < 3; ++i) {
      const int j = (i + 1) % 3;
      const Placed p = place(cylinder(kO, axes[i], 1.0), cylinder(kO, axes[j], 1.0), 2.0, loc);
      const SsiResult r = run(p);
      ASSERT_EQ(r.kind, SsiKind::Curves);
      ASSERT_EQ(r.curves.size(), 2u);
      const Vec3 centre = loc.apply_point(kO);
      const Vec3 ai = loc.apply_direction(axes[i]), aj = loc.apply_direction(axes[j]);
      for (const SectionCurve& c : r.curves) {
        EXPECT_TRUE(c.closed);
        EXPECT_FALSE(c.tangent);
        for (double t : samples(c)) {
          const Vec3 q = c.curve->point(t) - centre;
          // |q × axis| = r on both cylinders.
          EXPECT_NEAR(q.cross(ai).norm(), loc.scale(), 1e-10 * p.size);
          EXPECT_NEAR(q.cross(aj).norm(), loc.scale(), 1e-10 * p.size);
        }
      }
    }
  }
}

// ---- Clipping and determinism -----------------------------------------------------------

TEST(SurfaceIntersection, LinesAreClippedToTheGrownBox) {
  const SurfacePtr a = plane(kO, kZ);
  const SurfacePtr b = plane(kO, kY);
  BoundingBox clip;
  clip.add(Vec3(-1, -1, -1));
  clip.add(Vec3(3, 1, 1));
  const SsiResult r = intersect_surfaces(*a, *b, clip, kTolerance);
  ASSERT_EQ(r.curves.size(), 1u);
  const SectionCurve& c = r.curves[0];
  BoundingBox grown = clip;
  grown.enlarge(0.05 * clip.size().norm() + 2.0 * kTolerance);
  EXPECT_TRUE(grown.contains(c.curve->point(c.first)));
  EXPECT_TRUE(grown.contains(c.curve->point(c.last)));
  EXPECT_GE(std::abs(c.last - c.first), 4.0);  // covers the box along x

  BoundingBox far;
  far.add(Vec3(10, 10, 10));
  far.add(Vec3(11, 11, 11));
  EXPECT_TRUE(intersect_surfaces(*a, *b, far, kTolerance).curves.empty());
  // A surface far from the box gives nothing; so does a circle whose bounds miss the box.
  EXPECT_TRUE(
      intersect_surfaces(*cylinder(kO, kZ, 1.0), *sphere(Vec3(0, 0, 20), 1.5), clip, kTolerance)
          .curves.empty());
  EXPECT_TRUE(
      intersect_surfaces(*cylinder(kO, kZ, 1.0), *plane(Vec3(0, 0, 1.6), kZ), clip, kTolerance)
          .curves.empty());
  EXPECT_EQ(
      intersect_surfaces(*cylinder(kO, kZ, 1.0), *plane(Vec3(0, 0, 1.2), kZ), clip, kTolerance)
          .curves.size(),
      1u);
  EXPECT_TRUE(intersect_surfaces(*a, *b, BoundingBox(), kTolerance).curves.empty());
  EXPECT_EQ(intersect_surfaces(*a, *a, BoundingBox(), kTolerance).kind, SsiKind::Coincident);
}

TEST(SurfaceIntersection, NearlyTangentWithinToleranceIsTangent) {
  const SurfacePtr c = cylinder(kO, kZ, 1.0);
  BoundingBox clip;
  clip.add(Vec3(-2, -2, -2));
  clip.add(Vec3(2, 2, 2));
  const SsiResult inside =
      intersect_surfaces(*c, *plane(Vec3(1.0 - 0.5 * kTolerance, 0, 0), kX), clip, kTolerance);
  ASSERT_EQ(inside.curves.size(), 1u);
  EXPECT_TRUE(inside.curves[0].tangent);
  const SsiResult outside =
      intersect_surfaces(*c, *plane(Vec3(1.0 + 0.5 * kTolerance, 0, 0), kX), clip, kTolerance);
  ASSERT_EQ(outside.curves.size(), 1u);
  EXPECT_TRUE(outside.curves[0].tangent);
  EXPECT_EQ(
      intersect_surfaces(*c, *plane(Vec3(1.0 - 1e-3, 0, 0), kX), clip, kTolerance).curves.size(),
      2u);
  EXPECT_TRUE(
      intersect_surfaces(*c, *plane(Vec3(1.0 + 1e-3, 0, 0), kX), clip, kTolerance).curves.empty());
  // An axis tilted by less than tolerance / size is still parallel: lines, not an ellipse.
  const SsiResult tilted = intersect_surfaces(
      *c, *plane(Vec3(0.5, 0, 0), Vec3(1, 0, 0.01 * kTolerance)), clip, kTolerance);
  ASSERT_EQ(tilted.curves.size(), 2u);
  EXPECT_FALSE(tilted.curves[0].closed);
}

TEST(SurfaceIntersection, Deterministic) {
  const Placed p =
      place(torus(kO, kZ, 2.0, 0.5), cylinder(kO, kZ, 2.0), 4.0, placements(1401).back());
  const SsiResult r1 = run(p);
  const SsiResult r2 = run(p);
  ASSERT_EQ(r1.curves.size(), r2.curves.size());
  for (std::size_t i = 0; i < r1.curves.size(); ++i) {
    for (double t : samples(r1.curves[i])) {
      EXPECT_EQ(r1.curves[i].curve->point(t), r2.curves[i].curve->point(t));
    }
  }
}

}  // namespace
}  // namespace csgtile::kernel::detail
