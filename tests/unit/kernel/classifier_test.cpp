// Point classification for Booleans: every primitive under random similarity placements
// against closed-form inside tests, points on faces with their outward normals, rays aimed at
// edges / vertices / seams / poles / apexes (the recast logic), compounds, cavities, swept
// surfaces, determinism and throughput.

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <numbers>
#include <random>
#include <sstream>
#include <string>
#include <thread>

#include "boolean/classifier.h"
#include "boolean/line_surface.h"
#include "csgtile/kernel/explorer.h"
#include "csgtile/kernel/mass_properties.h"
#include "csgtile/kernel/primitives.h"
#include "random_shapes.h"

namespace csgtile::kernel::detail {
namespace {

constexpr std::uint64_t kSeed = 20261207;
constexpr double kPi = std::numbers::pi;
constexpr double kTolerance = 1e-7;
// Points closer than this to the boundary (world units) are not checked against the
// closed-form test: they are within the kernel's tolerances of it.
constexpr double kSkipBand = 1e-6;

// ---- closed-form solids (local frames of the builders) -----------------------------------

double segment_distance_2d(const Vec2& p, const Vec2& a, const Vec2& b) {
  const Vec2 ab = b - a;
  const double s = std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
  return (a + s * ab - p).norm();
}

bool in_ring(const Vec2& p, const std::vector<Vec2>& ring) {
  bool inside = false;
  for (std::size_t i = 0, j = ring.size() - 1; i < ring.size(); j = i++) {
    const Vec2 &a = ring[i], &b = ring[j];
    if ((a.y() > p.y()) != (b.y() > p.y()) &&
        p.x() < a.x() + (p.y() - a.y()) * (b.x() - a.x()) / (b.y() - a.y())) {
      inside = !inside;
    }
  }
  return inside;
}

// Signed distance estimate: negative inside, and |value| never above the true distance to
// the boundary (so skipping |value| < band skips every point near the boundary).
using DistanceEstimate = std::function<double(const Vec3&)>;

DistanceEstimate extrusion_estimate(std::vector<std::vector<Vec2>> rings, double h) {
  return [rings = std::move(rings), h](const Vec3& p) {
    const Vec2 xy(p.x(), p.y());
    bool in = false;
    double d2 = std::numeric_limits<double>::infinity();
    for (const auto& ring : rings) {
      if (in_ring(xy, ring)) in = !in;
      for (std::size_t i = 0; i < ring.size(); ++i) {
        d2 = std::min(d2, segment_distance_2d(xy, ring[i], ring[(i + 1) % ring.size()]));
      }
    }
    const bool in_z = p.z() > 0 && p.z() < h;
    if (in && in_z) return -std::min(d2, std::min(p.z(), h - p.z()));
    if (in) return p.z() <= 0 ? -p.z() : p.z() - h;
    return d2;
  };
}

// Revolution about Z of a (rho, z) profile by `angle`.
DistanceEstimate revolution_estimate(std::vector<Vec2> profile, double angle) {
  return [profile = std::move(profile), angle](const Vec3& p) {
    const Vec2 rz(std::hypot(p.x(), p.y()), p.z());
    double d2 = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < profile.size(); ++i) {
      const Vec2 &a = profile[i], &b = profile[(i + 1) % profile.size()];
      if (a.x() == 0 && b.x() == 0) continue;  // on the axis: bounds nothing
      d2 = std::min(d2, segment_distance_2d(rz, a, b));
    }
    bool in = in_ring(rz, profile);
    if (angle < 2 * kPi) {
      double theta = std::atan2(p.y(), p.x());
      if (theta < 0) theta += 2 * kPi;
      in = in && theta <= angle;
      // Distances to the planes of the two end caps bound the distance to the caps.
      d2 = std::min(
          {d2, std::abs(p.y()), std::abs(-p.x() * std::sin(angle) + p.y() * std::cos(angle))});
    }
    return in ? -d2 : d2;
  };
}

struct Model {
  std::string name;
  Shape local;
  DistanceEstimate estimate;
};

std::vector<Vec2> star(std::mt19937_64& rng, int n, double r_min, double r_max) {
  std::uniform_real_distribution<double> radius(r_min, r_max);
  std::vector<Vec2> ring;
  for (int i = 0; i < n; ++i) {
    const double a = 2 * kPi * i / n, r = radius(rng);
    ring.emplace_back(r * std::cos(a), r * std::sin(a));
  }
  return ring;
}

enum class Variant {
  Box,
  Cylinder,
  ConeApex,
  Frustum,
  Sphere,
  Torus,
  ExtrusionWithHole,
  RevolutionFull,
  RevolutionPartial
};
constexpr Variant kVariants[] = {Variant::Box,
                                 Variant::Cylinder,
                                 Variant::ConeApex,
                                 Variant::Frustum,
                                 Variant::Sphere,
                                 Variant::Torus,
                                 Variant::ExtrusionWithHole,
                                 Variant::RevolutionFull,
                                 Variant::RevolutionPartial};

Model make_model(Variant variant, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> size(0.5, 10.0);
  switch (variant) {
    case Variant::Box: {
      const double dx = size(rng), dy = size(rng), dz = size(rng);
      return {"box", make_box(dx, dy, dz).value(),
              extrusion_estimate({{{0, 0}, {dx, 0}, {dx, dy}, {0, dy}}}, dz)};
    }
    case Variant::Cylinder: {
      const double r = size(rng), h = size(rng);
      return {"cylinder", make_cylinder(r, h).value(),
              revolution_estimate({{0, 0}, {r, 0}, {r, h}, {0, h}}, 2 * kPi)};
    }
    case Variant::ConeApex: {
      const double r = size(rng), h = size(rng);
      if (std::bernoulli_distribution(0.5)(rng)) {
        return {"cone_apex_up", make_cone(r, 0, h).value(),
                revolution_estimate({{0, 0}, {r, 0}, {0, h}}, 2 * kPi)};
      }
      return {"cone_apex_down", make_cone(0, r, h).value(),
              revolution_estimate({{0, 0}, {r, h}, {0, h}}, 2 * kPi)};
    }
    case Variant::Frustum: {
      const double r1 = size(rng), r2 = size(rng), h = size(rng);
      return {"frustum", make_cone(r1, r2, h).value(),
              revolution_estimate({{0, 0}, {r1, 0}, {r2, h}, {0, h}}, 2 * kPi)};
    }
    case Variant::Sphere: {
      const double r = size(rng);
      return {"sphere", make_sphere(r).value(), [r](const Vec3& p) { return p.norm() - r; }};
    }
    case Variant::Torus: {
      const double small = size(rng) * 0.5;
      const double big = small * std::uniform_real_distribution<double>(1.1, 4.0)(rng);
      return {"torus", make_torus(big, small).value(), [big, small](const Vec3& p) {
                return std::hypot(std::hypot(p.x(), p.y()) - big, p.z()) - small;
              }};
    }
    case Variant::ExtrusionWithHole: {
      const int n = std::uniform_int_distribution<int>(5, 12)(rng);
      std::vector<Vec2> outer = star(rng, n, 4.0, 10.0);
      const double c = std::cos(0.3), s = std::sin(0.3), half = 1.5;
      std::vector<Vec2> hole;
      for (const Vec2& corner :
           {Vec2(-half, -half), Vec2(half, -half), Vec2(half, half), Vec2(-half, half)}) {
        hole.emplace_back(c * corner.x() - s * corner.y(), s * corner.x() + c * corner.y());
      }
      const double h = size(rng);
      return {"extrusion_with_hole", make_extrusion(outer, {hole}, h).value(),
              extrusion_estimate({outer, hole}, h)};
    }
    case Variant::RevolutionFull:
    case Variant::RevolutionPartial: {
      // An L-shaped profile, touching the axis half of the time.
      const double r0 = std::bernoulli_distribution(0.5)(rng) ? 0.0 : size(rng) * 0.3;
      const double w = size(rng), h = size(rng);
      const std::vector<Vec2> profile{{r0, 0},           {r0 + w, 0},
                                      {r0 + w, 0.4 * h}, {r0 + 0.5 * w, 0.6 * h},
                                      {r0 + 0.5 * w, h}, {r0, h}};
      const bool full = variant == Variant::RevolutionFull;
      const double angle = full ? 2 * kPi : std::uniform_real_distribution<double>(0.4, 6.0)(rng);
      return {full ? "revolution_full" : "revolution_partial",
              make_revolution(profile, angle).value(), revolution_estimate(profile, angle)};
    }
  }
  return {};
}

struct Placed {
  Model model;
  Location placement;
  Shape shape;
  SolidClassifier classifier;
  // World-frame estimate.
  double estimate(const Vec3& world) const {
    return placement.scale() * model.estimate(placement.inverse().apply_point(world));
  }
};

Placed place(Model model, const Location& placement) {
  Shape shape = model.local.moved(placement);
  auto classifier = SolidClassifier::create(shape, kTolerance * std::max(1.0, placement.scale()));
  EXPECT_TRUE(classifier.ok()) << model.name << ": " << classifier.error().message;
  return {std::move(model), placement, shape, std::move(classifier).value()};
}

Containment expected(double estimate) {
  return estimate < 0 ? Containment::Inside : Containment::Outside;
}

std::string describe(const Placed& c, const Vec3& p) {
  std::ostringstream s;
  s.precision(17);
  s << c.model.name << " at (" << p.x() << ", " << p.y() << ", " << p.z() << "), estimate "
    << c.estimate(p);
  return s.str();
}

// ---- random points -------------------------------------------------------------------------

// Uniform points in the solid's local bounding box grown by 15%, placed in the world.
std::vector<Vec3> sample_points(const Placed& c, int count, std::mt19937_64& rng) {
  BoundingBox box = bounding_box(c.model.local);
  box.enlarge(0.15 * box.size().maxCoeff());
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<Vec3> points;
  for (int i = 0; i < count; ++i) {
    points.push_back(
        c.placement.apply_point(box.min + Vec3(u(rng), u(rng), u(rng)).cwiseProduct(box.size())));
  }
  return points;
}

TEST(Classifier, RandomPointsMatchClosedFormForEveryPrimitive) {
  std::mt19937_64 rng(kSeed);
  for (Variant variant : kVariants) {
    for (int placement = 0; placement < 6; ++placement) {
      const Placed c = place(make_model(variant, rng), test::random_similarity(rng));
      int checked = 0, inside = 0;
      for (const Vec3& p : sample_points(c, 400, rng)) {
        const double e = c.estimate(p);
        if (std::abs(e) < kSkipBand) continue;
        ++checked;
        inside += e < 0;
        ASSERT_EQ(c.classifier.classify(p), expected(e)) << describe(c, p);
      }
      EXPECT_GT(checked, 300) << c.model.name;
      EXPECT_GT(inside, 0) << c.model.name;
    }
  }
}

// Points on the axis of revolved solids (the surfaces' inversions are singular there).
TEST(Classifier, PointsOnAxesClassifyRight) {
  std::mt19937_64 rng(kSeed + 1);
  for (Variant variant : {Variant::Cylinder, Variant::ConeApex, Variant::Frustum, Variant::Sphere,
                          Variant::Torus, Variant::RevolutionFull, Variant::RevolutionPartial}) {
    for (int placement = 0; placement < 4; ++placement) {
      const Placed c = place(make_model(variant, rng), test::random_similarity(rng));
      const BoundingBox local = bounding_box(c.model.local);
      for (int i = 0; i <= 40; ++i) {
        const double z = local.min.z() - 1.0 + (local.size().z() + 2.0) * i / 40.0;
        const Vec3 p = c.placement.apply_point(Vec3(0, 0, z));
        const double e = c.estimate(p);
        if (std::abs(e) < kSkipBand) continue;
        ASSERT_EQ(c.classifier.classify(p), expected(e)) << describe(c, p);
      }
    }
  }
}

// ---- points on faces ----------------------------------------------------------------------

TEST(Classifier, PointsOnFacesAreOnBoundaryWithOutwardNormal) {
  std::mt19937_64 rng(kSeed + 2);
  for (Variant variant : kVariants) {
    for (int placement = 0; placement < 3; ++placement) {
      const Placed c = place(make_model(variant, rng), test::random_similarity(rng));
      const double size = bounding_box(c.shape).size().maxCoeff();
      const double step = 1e-4 * size;
      for (std::size_t f = 0; f < c.classifier.face_count(); ++f) {
        const FaceQuery& face = c.classifier.face(f);
        const ParamBox& pb = face.parameter_box();
        std::uniform_real_distribution<double> uu(pb.u0, pb.u1), vv(pb.v0, pb.v1);
        int tested = 0;
        for (int attempt = 0; attempt < 400 && tested < 25; ++attempt) {
          const Vec2 uv(uu(rng), vv(rng));
          if (face.locate_uv(uv) != Containment::Inside) continue;
          const Vec3 p = face.location().apply_point(face.surface().point(uv.x(), uv.y()));
          ASSERT_EQ(c.classifier.classify(p), Containment::OnBoundary) << describe(c, p);
          const auto n = c.classifier.boundary_normal(p);
          ASSERT_TRUE(n.has_value()) << describe(c, p);
          EXPECT_NEAR(n->norm(), 1.0, 1e-12);
          // The normal is outward: a small step along it leaves the solid, against it enters.
          // Near an edge or an apex a step can cross another face: those points are skipped,
          // and every face must keep some.
          const double out = c.estimate(p + step * *n), in = c.estimate(p - step * *n);
          if (!(out > 0.5 * step && in < -0.5 * step)) continue;
          ++tested;
          EXPECT_EQ(c.classifier.classify(p + step * *n), Containment::Outside) << describe(c, p);
          EXPECT_EQ(c.classifier.classify(p - step * *n), Containment::Inside) << describe(c, p);
        }
        EXPECT_GT(tested, 0) << c.model.name << " face " << f;
      }
    }
  }
}

// Points just off the faces (down to a few tolerances away), on both sides.
TEST(Classifier, PointsNearFacesClassifyRight) {
  std::mt19937_64 rng(kSeed + 9);
  std::uniform_real_distribution<double> log_offset(std::log(3e-6), std::log(1e-2));
  for (Variant variant : kVariants) {
    for (int placement = 0; placement < 3; ++placement) {
      const Placed c = place(make_model(variant, rng), test::random_similarity(rng));
      for (std::size_t f = 0; f < c.classifier.face_count(); ++f) {
        const FaceQuery& face = c.classifier.face(f);
        const ParamBox& pb = face.parameter_box();
        std::uniform_real_distribution<double> uu(pb.u0, pb.u1), vv(pb.v0, pb.v1);
        for (int attempt = 0; attempt < 300; ++attempt) {
          const Vec2 uv(uu(rng), vv(rng));
          if (face.locate_uv(uv) != Containment::Inside) continue;
          const Vec3 on = face.location().apply_point(face.surface().point(uv.x(), uv.y()));
          const Vec3 n = face.outward_normal(uv);
          const double offset = std::exp(log_offset(rng)) * (attempt % 2 == 0 ? 1.0 : -1.0);
          const Vec3 p = on + offset * n;
          const double e = c.estimate(p);
          if (std::abs(e) < kSkipBand) continue;
          ASSERT_EQ(c.classifier.classify(p), expected(e))
              << describe(c, p) << " offset " << offset;
        }
      }
    }
  }
}

// ---- rays that hit edges, vertices, seams, poles, apexes ------------------------------------

// Targets on the boundary's edges and vertices (seams, poles and apexes included).
std::vector<Vec3> edge_targets(const Shape& shape) {
  std::vector<Vec3> targets;
  const ShapeIndex vertices = map_child_shapes(shape, ShapeKind::Vertex);
  const ShapeIndex edges = map_child_shapes(shape, ShapeKind::Edge);
  for (const Shape& v : vertices.shapes()) targets.push_back(vertex_point(v));
  for (const Shape& e : edges.shapes()) {
    const EdgeData& d = *e.body().edge();
    if (d.degenerate()) continue;
    for (double s : {0.5, 0.25}) {
      const CurvePtr curve = d.curve->transformed(e.location());
      const double scale = curve->kind() == CurveKind::Line ? e.location().scale() : 1.0;
      targets.push_back(curve->point(scale * (d.first + s * (d.last - d.first))));
    }
  }
  return targets;
}

TEST(Classifier, RaysThroughEdgesVerticesSeamsAndPolesAreRecast) {
  std::mt19937_64 rng(kSeed + 3);
  int points = 0, recast = 0, voted = 0;
  for (Variant variant : kVariants) {
    for (int placement = 0; placement < 3; ++placement) {
      const Placed c = place(make_model(variant, rng), test::random_similarity(rng));
      const double size = bounding_box(c.shape).size().maxCoeff();
      const Vec3 first_ray = c.classifier.ray_directions().front();
      for (const Vec3& target : edge_targets(c.shape)) {
        EXPECT_EQ(c.classifier.classify(target), Containment::OnBoundary) << describe(c, target);
        EXPECT_TRUE(c.classifier.boundary_normal(target).has_value()) << describe(c, target);
        // Points from which the first ray runs exactly through the target, inside and outside.
        for (double lambda : {0.03, 0.1, 0.3, 0.7, 1.5}) {
          const Vec3 p = target - lambda * size * first_ray;
          const double e = c.estimate(p);
          if (std::abs(e) < kSkipBand) continue;
          ClassifyStats stats;
          ASSERT_EQ(c.classifier.classify(p, &stats), expected(e))
              << describe(c, p) << " (ray through an edge)";
          ++points;
          recast += stats.rays > 1;
          voted += stats.voted;
        }
      }
    }
  }
  // The first ray of most points is ambiguous (it may meet the target from outside the solid,
  // where nothing is hit first, or be stopped by the slab test): the recast logic ran.
  EXPECT_GT(points, 500);
  EXPECT_GT(recast, points / 3) << recast << " of " << points;
  EXPECT_EQ(voted, 0);
}

// ---- compounds and cavities --------------------------------------------------------------

TEST(Classifier, CompoundOfTwoDisjointSolidsIsTheirUnion) {
  const Shape a = make_sphere(2.0).value();
  const Shape b = make_box(2, 2, 2).value().moved(Location::translation(Vec3(5, 0, 0)));
  const Shape both = ShapeFactory::compound({a, b}).value();
  const auto c = SolidClassifier::create(both, kTolerance).value();
  EXPECT_EQ(c.classify(Vec3(0, 0, 0)), Containment::Inside);
  EXPECT_EQ(c.classify(Vec3(6, 1, 1)), Containment::Inside);
  EXPECT_EQ(c.classify(Vec3(3.5, 1, 1)), Containment::Outside);
  EXPECT_EQ(c.classify(Vec3(2, 0, 0)), Containment::OnBoundary);
  EXPECT_EQ(c.classify(Vec3(5, 1, 1)), Containment::OnBoundary);
  std::mt19937_64 rng(kSeed + 4);
  std::uniform_real_distribution<double> x(-3, 8), yz(-3, 3);
  for (int i = 0; i < 2000; ++i) {
    const Vec3 p(x(rng), yz(rng), yz(rng));
    const double da = p.norm() - 2.0;
    const Vec3 q = p - Vec3(5, 0, 0);
    const double db = std::max({-q.x(), q.x() - 2, -q.y(), q.y() - 2, -q.z(), q.z() - 2});
    if (std::abs(da) < kSkipBand || std::abs(db) < kSkipBand) continue;
    ASSERT_EQ(c.classify(p), da < 0 || db < 0 ? Containment::Inside : Containment::Outside)
        << p.transpose();
  }
}

TEST(Classifier, OverlappingSolidsInACompoundClassifyAsTheirUnion) {
  const Shape a = make_box(2, 2, 2).value();
  const Shape b = make_box(2, 2, 2).value().moved(Location::translation(Vec3(1, 0.5, 0.5)));
  const auto c =
      SolidClassifier::create(ShapeFactory::compound({a, b}).value(), kTolerance).value();
  EXPECT_EQ(c.classify(Vec3(1.5, 1, 1)), Containment::Inside);  // in both: parity would say out
  EXPECT_EQ(c.classify(Vec3(2, 1, 1)), Containment::Inside);    // on a's face, inside b
  EXPECT_EQ(c.classify(Vec3(2.5, 1, 1)), Containment::Inside);
  EXPECT_EQ(c.classify(Vec3(3, 1, 1)), Containment::OnBoundary);
  EXPECT_EQ(c.classify(Vec3(3.5, 1, 1)), Containment::Outside);
}

// A city block: a grid of overlapping boxes and cylinders in one compound (the trees keep a
// query near the solids it can meet).
TEST(Classifier, ManyOverlappingSolidsInACompound) {
  std::mt19937_64 rng(kSeed + 10);
  std::uniform_real_distribution<double> unit(0, 1);
  struct Part {
    bool box;
    Vec3 corner;  // box: min corner; cylinder: base centre
    Vec3 size;    // box: sizes; cylinder: (r, r, h)
  };
  std::vector<Part> parts;
  std::vector<Shape> solids;
  for (int i = 0; i < 30; ++i) {
    for (int j = 0; j < 30; ++j) {
      const Vec3 at(i * 10.0 + 3 * unit(rng), j * 10.0 + 3 * unit(rng), 0);
      if ((i + j) % 3 != 0) {
        const Vec3 size(5 + 8 * unit(rng), 5 + 8 * unit(rng), 5 + 20 * unit(rng));
        parts.push_back({true, at, size});
        solids.push_back(
            make_box(size.x(), size.y(), size.z()).value().moved(Location::translation(at)));
      } else {
        const double r = 2 + 4 * unit(rng), h = 5 + 20 * unit(rng);
        parts.push_back({false, at, Vec3(r, r, h)});
        solids.push_back(make_cylinder(r, h).value().moved(Location::translation(at)));
      }
    }
  }
  const auto c =
      SolidClassifier::create(ShapeFactory::compound(solids).value(), kTolerance).value();
  auto estimate = [&](const Vec3& p) {
    double best = std::numeric_limits<double>::infinity();  // min over parts: the union
    bool inside = false;
    for (const Part& part : parts) {
      const Vec3 q = p - part.corner;
      double d;
      if (part.box) {
        d = std::max({-q.x(), q.x() - part.size.x(), -q.y(), q.y() - part.size.y(), -q.z(),
                      q.z() - part.size.z()});
      } else {
        d = std::max({std::hypot(q.x(), q.y()) - part.size.x(), -q.z(), q.z() - part.size.z()});
      }
      inside = inside || d < 0;
      best = std::min(best, std::abs(d));
    }
    return inside ? -best : best;
  };
  std::vector<Vec3> points;
  for (int i = 0; i < 3000; ++i)
    points.emplace_back(310 * unit(rng), 310 * unit(rng), 30 * unit(rng));
  std::vector<Containment> got;
  const auto start = std::chrono::steady_clock::now();
  for (const Vec3& p : points) got.push_back(c.classify(p));
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("900-solid compound (%zu faces): %.0f classifications per second\n", c.face_count(),
              static_cast<double>(points.size()) / seconds);
  for (std::size_t i = 0; i < points.size(); ++i) {
    const double e = estimate(points[i]);
    if (std::abs(e) < kSkipBand) continue;
    ASSERT_EQ(got[i], e < 0 ? Containment::Inside : Containment::Outside) << points[i].transpose();
  }
}

TEST(Classifier, CavityIsOutside) {
  // A box shell and a reversed sphere shell in one solid: material between them.
  const Shape box = make_box(10, 10, 10).value();
  const Shape sphere = make_sphere(3.0).value().moved(Location::translation(Vec3(5, 5, 5)));
  const Shape box_shell = Explorer(box, ShapeKind::Shell).begin().operator*();
  const Shape sphere_shell = Explorer(sphere, ShapeKind::Shell).begin().operator*();
  const Shape solid = ShapeFactory::solid({box_shell, sphere_shell.reversed()}).value();
  for (const Location& placement :
       {Location(), Location::translation(Vec3(-40, 3, 7)) *
                        Location::rotation(Vec3::Zero(), Vec3(1, 2, 3), 0.7) *
                        Location::scaling(1.7)}) {
    const auto c = SolidClassifier::create(solid.moved(placement), kTolerance).value();
    auto at = [&](const Vec3& p) { return placement.apply_point(p); };
    EXPECT_EQ(c.classify(at(Vec3(5, 5, 5))), Containment::Outside);
    EXPECT_EQ(c.classify(at(Vec3(6, 5.5, 4))), Containment::Outside);
    EXPECT_EQ(c.classify(at(Vec3(1, 1, 1))), Containment::Inside);
    EXPECT_EQ(c.classify(at(Vec3(5, 5, 8.5))), Containment::Inside);
    EXPECT_EQ(c.classify(at(Vec3(11, 5, 5))), Containment::Outside);
    // On the cavity's wall the outward normal of the solid points into the cavity.
    const Vec3 wall = at(Vec3(5, 5, 8));
    EXPECT_EQ(c.classify(wall), Containment::OnBoundary);
    const auto n = c.boundary_normal(wall);
    ASSERT_TRUE(n.has_value());
    EXPECT_LT((*n - placement.apply_direction(Vec3(0, 0, -1))).norm(), 1e-9);
    std::mt19937_64 rng(kSeed + 5);
    std::uniform_real_distribution<double> u(-1, 11);
    for (int i = 0; i < 2000; ++i) {
      const Vec3 p(u(rng), u(rng), u(rng));
      const double to_box = std::max({-p.x(), p.x() - 10, -p.y(), p.y() - 10, -p.z(), p.z() - 10});
      const double to_sphere = (p - Vec3(5, 5, 5)).norm() - 3.0;
      if (std::abs(to_box) < kSkipBand || std::abs(to_sphere) < kSkipBand) continue;
      ASSERT_EQ(c.classify(at(p)),
                to_box < 0 && to_sphere > 0 ? Containment::Inside : Containment::Outside)
          << p.transpose();
    }
  }
}

TEST(Classifier, EmptyShapeHasNothingInside) {
  const auto c = SolidClassifier::create(ShapeFactory::compound({}).value(), kTolerance);
  ASSERT_TRUE(c.ok());
  EXPECT_EQ(c->classify(Vec3::Zero()), Containment::Outside);
}

TEST(Classifier, CreateRejectsBadArguments) {
  EXPECT_EQ(SolidClassifier::create(Shape(), kTolerance).error().code, ErrorCode::InvalidArgument);
  const Shape box = make_box(1, 1, 1).value();
  EXPECT_EQ(SolidClassifier::create(box, 0.0).error().code, ErrorCode::InvalidArgument);
  EXPECT_EQ(SolidClassifier::create(box, NAN).error().code, ErrorCode::InvalidArgument);
  EXPECT_EQ(SolidClassifier::create(box, kTolerance, {.seed = 1, .max_rays = 0}).error().code,
            ErrorCode::InvalidArgument);
  EXPECT_EQ(FaceQuery::create(box).error().code, ErrorCode::InvalidArgument);
}

// ---- swept surfaces ----------------------------------------------------------------------

// The same solid with each curved face's surface replaced by an extrusion or revolution with
// the same parametrisation (so the pcurves still hold): exercises the swept-surface paths.
SurfacePtr swept_equivalent(const Surface& s, int flavour) {
  switch (s.kind()) {
    case SurfaceKind::Cylinder: {
      const auto& c = static_cast<const CylinderSurface&>(s);
      const Frame& f = c.frame();
      const double r = c.radius();
      if (flavour % 3 == 0)
        return std::make_shared<ExtrusionSurface>(std::make_shared<CircleCurve>(f, r), f.z);
      if (flavour % 3 == 1) {
        return std::make_shared<ExtrusionSurface>(
            std::make_shared<TrigCurve>(f.origin, r * f.x, r * f.y), f.z);
      }
      // Polyline meridian with unit steps up the axis from height 0: its parameter is the
      // height, like the cylinder's v (heights stay below 10 here).
      std::vector<Vec3> points;
      for (int k = 0; k <= 12; ++k) points.push_back(f.origin + r * f.x + k * f.z);
      return std::make_shared<RevolutionSurface>(std::make_shared<PolylineCurve>(points, 0.0),
                                                 f.origin, f.z);
    }
    case SurfaceKind::Cone: {
      const auto& c = static_cast<const ConeSurface&>(s);
      const Frame& f = c.frame();
      const double phi = c.semi_angle();
      return std::make_shared<RevolutionSurface>(
          std::make_shared<LineCurve>(f.origin + c.reference_radius() * f.x,
                                      std::sin(phi) * f.x + std::cos(phi) * f.z),
          f.origin, f.z);
    }
    case SurfaceKind::Sphere: {
      const auto& c = static_cast<const SphereSurface&>(s);
      Frame meridian;
      meridian.origin = c.frame().origin;
      meridian.x = c.frame().x;
      meridian.y = c.frame().z;
      meridian.z = meridian.x.cross(meridian.y);
      CurvePtr curve =
          flavour % 2 == 0
              ? CurvePtr(std::make_shared<CircleCurve>(meridian, c.radius()))
              : CurvePtr(std::make_shared<TrigCurve>(meridian.origin, c.radius() * meridian.x,
                                                     c.radius() * meridian.y));
      return std::make_shared<RevolutionSurface>(curve, c.frame().origin, c.frame().z);
    }
    case SurfaceKind::Torus: {
      const auto& c = static_cast<const TorusSurface&>(s);
      Frame meridian;
      meridian.origin = c.frame().origin + c.major_radius() * c.frame().x;
      meridian.x = c.frame().x;
      meridian.y = c.frame().z;
      meridian.z = meridian.x.cross(meridian.y);
      return std::make_shared<RevolutionSurface>(
          std::make_shared<CircleCurve>(meridian, c.minor_radius()), c.frame().origin, c.frame().z);
    }
    default:
      return nullptr;
  }
}

Shape with_swept_surfaces(const Shape& solid, int flavour) {
  std::vector<Shape> faces;
  for (const Shape& face : Explorer(solid, ShapeKind::Face)) {
    const FaceData& data = *face.body().face();
    const SurfacePtr swept = swept_equivalent(*data.surface, flavour);
    if (swept == nullptr) {
      faces.push_back(face);
      continue;
    }
    const Shape body = face.oriented(Orientation::Forward);
    auto rebuilt = ShapeFactory::face(swept, body.children(), data.pcurves, data.tolerance);
    EXPECT_TRUE(rebuilt.ok());
    faces.push_back(rebuilt.value().located(face.location()).oriented(face.orientation()));
  }
  return ShapeFactory::solid({ShapeFactory::shell(faces).value()}).value();
}

TEST(Classifier, SweptSurfacesClassifyLikeTheQuadricsTheyEqual) {
  std::mt19937_64 rng(kSeed + 6);
  int flavour = 0;
  for (Variant variant : {Variant::Cylinder, Variant::ConeApex, Variant::Frustum, Variant::Sphere,
                          Variant::Torus, Variant::RevolutionFull}) {
    for (int placement = 0; placement < 4; ++placement, ++flavour) {
      Model model = make_model(variant, rng);
      model.local = with_swept_surfaces(model.local, flavour);
      model.name += "_swept" + std::to_string(flavour);
      const Placed c = place(std::move(model), test::random_similarity(rng));
      for (const Vec3& p : sample_points(c, 300, rng)) {
        const double e = c.estimate(p);
        if (std::abs(e) < kSkipBand) continue;
        ASSERT_EQ(c.classifier.classify(p), expected(e)) << describe(c, p);
      }
    }
  }
}

// Regression (stress seed 101, cylinder_swept14): a ray nearly perpendicular to a revolution
// axis; eliminating the ray parameter divided by its tiny axial component, and the unpolished
// root fell outside the face's box window and was lost.
TEST(Classifier, RevolutionHitsOfARayNearlyPerpendicularToTheAxisArePolished) {
  const double r = 8.937;
  std::vector<Vec3> meridian;
  for (int k = 0; k <= 12; ++k) meridian.emplace_back(r, 0, k);
  const RevolutionSurface surface(std::make_shared<PolylineCurve>(meridian, 0.0), Vec3::Zero(),
                                  Vec3::UnitZ());
  const Vec3 origin(-20, 3, 0.8456);
  const Vec3 direction = Vec3(1, 0, 3.9e-6).normalized();
  LineSurfaceIntersection out;
  intersect_line_surface(surface, origin, direction, 0.0, 100.0, {0, 2 * kPi, 0, 12}, kTolerance,
                         out);
  ASSERT_FALSE(out.degenerate);
  ASSERT_EQ(out.hits.size(), 2u);
  for (const LineSurfaceHit& hit : out.hits) {
    const Vec3 x = origin + hit.t * direction;
    EXPECT_NEAR(std::hypot(x.x(), x.y()), r, 1e-10);
    EXPECT_LT((surface.point(hit.uv.x(), hit.uv.y()) - x).norm(), 1e-10);
  }
}

// ---- face domains --------------------------------------------------------------------------

TEST(Classifier, FaceWithoutSeamIsTheBandBetweenItsCircles) {
  // A cylinder band bounded by two full circles and no seam: both loops are open by one
  // period in u.
  const double r = 2.0, h = 3.0;
  Frame bottom_frame, top_frame;
  top_frame.origin = Vec3(0, 0, h);
  const Shape v0 = ShapeFactory::vertex(Vec3(r, 0, 0), kTolerance).value();
  const Shape v1 = ShapeFactory::vertex(Vec3(r, 0, h), kTolerance).value();
  const Shape bottom = ShapeFactory::edge(std::make_shared<CircleCurve>(bottom_frame, r), 0,
                                          2 * kPi, v0, v0, kTolerance)
                           .value();
  const Shape top = ShapeFactory::edge(std::make_shared<CircleCurve>(top_frame, r), 0, 2 * kPi, v1,
                                       v1, kTolerance)
                        .value();
  const Shape face = ShapeFactory::face(std::make_shared<CylinderSurface>(Frame(), r),
                                        {ShapeFactory::wire({bottom}).value(),
                                         ShapeFactory::wire({top.reversed()}).value()},
                                        {{std::make_shared<Line2d>(Vec2(0, 0), Vec2(1, 0))},
                                         {std::make_shared<Line2d>(Vec2(0, h), Vec2(1, 0))}},
                                        kTolerance)
                         .value();
  const FaceQuery q = FaceQuery::create(face).value();
  EXPECT_TRUE(q.contains_uv(Vec2(1.0, 1.5)));
  EXPECT_TRUE(q.contains_uv(Vec2(1.0 + 2 * kPi, 1.5)));  // another period
  EXPECT_TRUE(q.contains_uv(Vec2(-1.0, 0.1)));
  EXPECT_FALSE(q.contains_uv(Vec2(1.0, 3.1)));
  EXPECT_FALSE(q.contains_uv(Vec2(1.0, -0.1)));
  EXPECT_EQ(q.locate_uv(Vec2(1.0, 0.0)), Containment::OnBoundary);
}

TEST(Classifier, CircularHoleInAPlanarFaceIsExactNearItsRim) {
  // A square with a circular hole (pcurve: a clockwise Circle2d): points just inside and just
  // outside the rim, far closer than any fixed sampling of the circle could resolve.
  const double r = 1.0;
  const Shape vc = ShapeFactory::vertex(Vec3(r, 0, 0), kTolerance).value();
  const Shape rim =
      ShapeFactory::edge(std::make_shared<CircleCurve>(Frame(), r), 0, 2 * kPi, vc, vc, kTolerance)
          .value();
  std::vector<Shape> corners;
  const Vec3 square[] = {{-3, -3, 0}, {3, -3, 0}, {3, 3, 0}, {-3, 3, 0}};
  for (const Vec3& p : square) corners.push_back(ShapeFactory::vertex(p, kTolerance).value());
  std::vector<Shape> sides;
  std::vector<Curve2dPtr> side_curves;
  for (int i = 0; i < 4; ++i) {
    const Vec3 a = square[i], b = square[(i + 1) % 4];
    sides.push_back(ShapeFactory::edge(std::make_shared<LineCurve>(a, b - a), 0, 6,
                                       corners[static_cast<std::size_t>(i)],
                                       corners[static_cast<std::size_t>((i + 1) % 4)], kTolerance)
                        .value());
    side_curves.push_back(
        std::make_shared<Line2d>(Vec2(a.x(), a.y()), Vec2(b.x() - a.x(), b.y() - a.y()) / 6));
  }
  const Shape face =
      ShapeFactory::face(
          std::make_shared<PlaneSurface>(Frame()),
          {ShapeFactory::wire(sides).value(), ShapeFactory::wire({rim.reversed()}).value()},
          {side_curves, {std::make_shared<Circle2d>(Vec2::Zero(), r)}}, kTolerance)
          .value();
  const FaceQuery q = FaceQuery::create(face).value();
  for (int i = 0; i < 100; ++i) {
    const double a = 0.0731 * i;
    const Vec2 dir(std::cos(a), std::sin(a));
    EXPECT_TRUE(q.contains_uv((r + 1e-9) * dir)) << a;
    EXPECT_FALSE(q.contains_uv((r - 1e-9) * dir)) << a;
    EXPECT_EQ(q.locate_uv(r * dir), Containment::OnBoundary) << a;
  }
  EXPECT_FALSE(q.contains_uv(Vec2(3.5, 0)));
  EXPECT_TRUE(q.contains_uv(Vec2(2.5, 2.5)));
}

// ---- determinism, threads, speed ------------------------------------------------------------

TEST(Classifier, IsDeterministicAndThreadSafe) {
  std::mt19937_64 rng(kSeed + 7);
  const Placed c = place(make_model(Variant::Torus, rng), test::random_similarity(rng));
  BoundingBox box = bounding_box(c.shape);
  std::vector<Vec3> points;
  std::uniform_real_distribution<double> u(0, 1);
  for (int i = 0; i < 3000; ++i) {
    points.push_back(box.min + Vec3(u(rng), u(rng), u(rng)).cwiseProduct(box.size()));
  }
  std::vector<Containment> a(points.size()), b(points.size());
  std::thread t1([&] {
    for (std::size_t i = 0; i < points.size(); ++i) a[i] = c.classifier.classify(points[i]);
  });
  std::thread t2([&] {
    for (std::size_t i = 0; i < points.size(); ++i) b[i] = c.classifier.classify(points[i]);
  });
  t1.join();
  t2.join();
  EXPECT_EQ(a, b);
  const auto again = SolidClassifier::create(c.shape, c.classifier.tolerance()).value();
  for (std::size_t i = 0; i < points.size(); ++i) ASSERT_EQ(again.classify(points[i]), a[i]);
}

double classifications_per_second(const Shape& shape) {
  const auto c = SolidClassifier::create(shape, kTolerance).value();
  BoundingBox box = bounding_box(shape);
  box.enlarge(0.1 * box.size().maxCoeff());
  std::mt19937_64 rng(kSeed + 8);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<Vec3> points;
  for (int i = 0; i < 100000; ++i)
    points.push_back(box.min + Vec3(u(rng), u(rng), u(rng)).cwiseProduct(box.size()));
  int inside = 0;
  const auto start = std::chrono::steady_clock::now();
  for (const Vec3& p : points) inside += c.classify(p) == Containment::Inside;
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_GT(inside, 0);
  return static_cast<double>(points.size()) / seconds;
}

TEST(Classifier, Throughput) {
  const Location placement = Location::translation(Vec3(10, -20, 30)) *
                             Location::rotation(Vec3::Zero(), Vec3(1, 1, 0), 0.4);
  const double box = classifications_per_second(make_box(1, 2, 3).value().moved(placement));
  const double torus = classifications_per_second(make_torus(3, 1).value().moved(placement));
  const double cylinder = classifications_per_second(make_cylinder(1, 3).value().moved(placement));
  std::printf("classifications per second: box %.0f, cylinder %.0f, torus %.0f\n", box, cylinder,
              torus);
  RecordProperty("box_per_second", std::to_string(box));
  RecordProperty("torus_per_second", std::to_string(torus));
  // Loose floors (a slow sanitizer build still passes): the point is that it is not
  // pathologically slow.
  EXPECT_GT(box, 2e4);
  EXPECT_GT(torus, 1e4);
}

}  // namespace
}  // namespace csgtile::kernel::detail
