// Shape detection on exact clouds (CAD objects, issue #24): a narrow strip of a wide cylinder
// is a cylinder when the cloud's own noise is nil; a cylinder taken for a wide torus is the
// cylinder along the torus's tube; a flat cone taken for a wide sphere is a cone (by its
// normals); a cylinder's belt taken for a sphere within a noisy cloud's floor is a cylinder;
// a hole's wall seen as one ring of points is a cylinder; a flat face stays a plane; the
// connectivity scale keeps coplanar faces with a narrow gap apart; the faces of a polygonal
// prism are planes, not the cylinder around them; a filleted disc's wall, taken with the
// fillets' rims for a sphere, is a cylinder once the rims went back to the fillets; a box's
// rounded corner and edges, a few points each, are a sphere and three cylinders; a flat strip
// between two arcs, one free column between their rims, is a plane.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <vector>

#include "csgtile/fit/fit.h"
#include "csgtile/fit/segment.h"
#include "fit_clouds.h"

namespace csgtile::fit {
namespace {

using kernel::Vec3;
using testing::Cloud;

// Every scale option derived from the cloud (the exact-cloud rules need its own noise), types
// by evidence.
RansacOptions derived_with_evidence(std::uint64_t seed) {
  RansacOptions o;
  o.epsilon = 0.0;
  o.min_points = 0;
  o.max_radius = 0.0;
  o.by_evidence = true;
  o.seed = seed;
  return o;
}

// fit-cad.yaml's detection: derived scale, types by evidence, relabelling, probability 0.9999.
RansacOptions cad_options(std::uint64_t seed) {
  RansacOptions o = derived_with_evidence(seed);
  o.relabel = true;
  o.probability = 0.9999;
  return o;
}

// fit-cad.yaml's normals: 8 neighbours, sharp.
std::vector<Vec3> sharp_normals(const Cloud& c) {
  NormalOptions n;
  n.neighbours = 8;
  n.sharp = true;
  return estimate_normals(c.points, n);
}

// Exact points on a strip of a cylinder of radius 20, 2 wide and 4 long: 0.025 from flat at
// its middle, within the epsilon a plane needs, so the RANSAC takes it for a plane. With the
// epsilon derived from the cloud (its noise is nil) the evidence says cylinder; with an
// epsilon given (the noise unknown: edge points could be what bends the points) it stays a
// plane.
TEST(FitExactClouds, StripOfAWideCylinderIsACylinderOnExactPoints) {
  const double r = 20.0, half = 1.0 / r;  // 2 wide: an angle of 2/r
  const Cloud c =
      testing::cylinder_cloud(Vec3(0, 0, 0), Vec3::UnitZ(), r, 4.0, -half, half, 1200, 0.0, 11);
  NormalOptions n;
  n.neighbours = 8;
  const auto normals = estimate_normals(c.points, n);
  for (const double epsilon : {0.0, 0.05}) {
    SCOPED_TRACE(epsilon == 0.0 ? "derived epsilon" : "epsilon given");
    RansacOptions o = derived_with_evidence(3);
    o.epsilon = epsilon;
    const auto result = detect_shapes(c.points, normals, o);
    ASSERT_TRUE(result.ok()) << result.error().message;
    ASSERT_EQ(result->shapes.size(), 1U) << result->reason;
    const DetectedShape& s = result->shapes.front();
    EXPECT_GT(s.inliers.size(), 1150U);
    if (epsilon == 0.0) {
      ASSERT_EQ(s.surface.type, ShapeType::Cylinder);
      EXPECT_NEAR(s.surface.radius, r, 0.01 * r);
      EXPECT_GT(std::abs(s.surface.axis.z()), 0.9999);
    } else {
      EXPECT_EQ(s.surface.type, ShapeType::Plane);
    }
  }
}

// Narrower strips (radius 22, 0.6 and 0.4 wide, as the root of a gear between its teeth): their
// points stray from their plane by only 1–2 times, or a quarter to once, the residual floor of
// exact points (a twentieth of the derived epsilon), and the cylinder through them fits them
// to within rounding. Each strip is a cylinder: what tells it from a plane is that the
// cylinder's error is a small share of the plane's (a hundredth where the plane's is within the
// floor, which the criterion cannot see through), not that the plane's error is large.
TEST(FitExactClouds, NarrowStripOfAWideCylinderIsACylinder) {
  const double r = 22.0;
  struct Strip {
    double half_width;
    int points;
    double floors_from, floors_to;  // the plane's error, in floors
  };
  for (const Strip& strip : {Strip{0.3, 350, 1.0, 2.0}, Strip{0.2, 233, 0.25, 1.0}}) {
    SCOPED_TRACE("strip " + std::to_string(2.0 * strip.half_width) + " wide");
    const double half = strip.half_width / r;
    const Cloud c = testing::cylinder_cloud(Vec3(0, 0, 0), Vec3::UnitZ(), r, 4.0, -half, half,
                                            strip.points, 0.0, 12);
    NormalOptions n;
    n.neighbours = 8;
    const auto result =
        detect_shapes(c.points, estimate_normals(c.points, n), derived_with_evidence(3));
    ASSERT_TRUE(result.ok()) << result.error().message;
    ASSERT_EQ(result->shapes.size(), 1U) << result->reason;
    // The plane's error (0.149 a²/r for a strip of half-width a) against the floor.
    const double plane_rms = 0.149 * strip.half_width * strip.half_width / r;
    const double floor = result->epsilon / 20.0;
    EXPECT_GT(plane_rms, strip.floors_from * floor) << "epsilon " << result->epsilon;
    EXPECT_LT(plane_rms, strip.floors_to * floor) << "epsilon " << result->epsilon;
    const DetectedShape& s = result->shapes.front();
    EXPECT_GT(s.inliers.size(), static_cast<std::size_t>(strip.points * 98 / 100));
    ASSERT_EQ(s.surface.type, ShapeType::Cylinder);
    EXPECT_NEAR(s.surface.radius, r, 0.01 * r);
    EXPECT_GT(std::abs(s.surface.axis.z()), 0.9999);
  }
}

// A cylinder's wall is also a torus whose tube runs along a large circle: when a torus is what
// the RANSAC drew (here the only type it may draw), the cylinder along its tube (axis the
// circle's tangent) keeps the points with fewer parameters and replaces it.
TEST(FitExactClouds, CylinderTakenForAWideTorusIsACylinder) {
  const Vec3 axis = Vec3(1, 0.2, 0.1).normalized();
  const Cloud c = testing::cylinder_cloud(Vec3(0, 0, 1), axis, 0.5, 3.0, 0.0, 2.0, 3000, 0.0, 13);
  RansacOptions o = derived_with_evidence(5);
  o.shapes = {false, false, false, false, true};
  NormalOptions n;
  n.neighbours = 8;
  const auto result = detect_shapes(c.points, estimate_normals(c.points, n), o);
  ASSERT_TRUE(result.ok());
  ASSERT_FALSE(result->shapes.empty()) << result->reason;
  const DetectedShape& s = result->shapes.front();
  ASSERT_EQ(s.surface.type, ShapeType::Cylinder);  // was a torus of R 15.4 over 1 237 points
  EXPECT_NEAR(s.surface.radius, 0.5, 0.005);
  EXPECT_LT(testing::line_angle_deg(s.surface.axis, axis), 1.0);
  EXPECT_GT(s.inliers.size(), 2950U);
}

// A flat cone (half-angle 85°) seen on a belt is within epsilon of a wide sphere too, and the
// RANSAC draws that sphere first; the points' normals, all at 5° from the cone's axis, show
// the cone: fitted from them, it keeps the points and scores better.
TEST(FitExactClouds, FlatConeTakenForAWideSphereIsACone) {
  const Vec3 apex(0, 0, 1), axis = Vec3(0.1, 0.2, 1).normalized();
  const double angle = 85.0 * std::numbers::pi / 180.0;
  const Cloud c = testing::cone_cloud(apex, axis, angle, 1.0, 3.0, 3000, 0.0, 17);
  RansacOptions o = derived_with_evidence(5);
  NormalOptions n;
  n.neighbours = 8;
  const auto result = detect_shapes(c.points, estimate_normals(c.points, n), o);
  ASSERT_TRUE(result.ok());
  ASSERT_EQ(result->shapes.size(), 1U) << result->reason;
  const DetectedShape& s = result->shapes.front();
  ASSERT_EQ(s.surface.type, ShapeType::Cone);  // was a sphere of radius 291 over 2 639 points
  EXPECT_NEAR(s.surface.angle, angle, 0.01);
  EXPECT_LT((s.surface.point - apex).norm(), 0.01);
  EXPECT_GT(s.surface.axis.dot(axis), std::cos(0.5 * std::numbers::pi / 180.0));
  EXPECT_EQ(s.inliers.size(), c.points.size());
}

// A belt of a cylinder (radius 5, 0.6 high, exact) beside a scan of a noisy floor (σ 3 cm)
// that sets the cloud's noise estimate: the sphere through the belt's middle circle fits it
// within that noise, and so does the cylinder; below the floor the criterion cannot tell them
// apart, and the sphere has fewer parameters. The cylinder fits the belt to rounding, a tenth of
// the sphere's error and less: the belt is the cylinder, whichever the RANSAC drew first (the
// sphere with seeds 5 and 6, which stayed a sphere).
TEST(FitExactClouds, CylinderBeltTakenForASphereIsACylinder) {
  constexpr std::uint32_t kBelt = 400;
  Cloud c = testing::cylinder_cloud(Vec3(0, 0, 0), Vec3::UnitZ(), 5.0, 0.6, 0.0,
                                    2.0 * std::numbers::pi, kBelt, 0.0, 31);
  c.append(
      testing::rectangle_cloud(Vec3(10, -10, -3), Vec3(20, 0, 0), Vec3(0, 20, 0), 0.2, 0.03, 32));
  NormalOptions n;
  n.neighbours = 8;
  const auto normals = estimate_normals(c.points, n);
  for (const std::uint64_t seed : {1, 2, 3, 4, 5, 6, 7, 8}) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const auto result = detect_shapes(c.points, normals, derived_with_evidence(seed));
    ASSERT_TRUE(result.ok());
    EXPECT_GT(result->noise, 0.01);
    int belts = 0;
    for (const auto& s : result->shapes) {
      if (s.inliers.empty() || s.inliers.front() >= kBelt) continue;
      ++belts;
      EXPECT_EQ(s.surface.type, ShapeType::Cylinder) << shape_type_name(s.surface.type);
      EXPECT_EQ(s.inliers.size(), kBelt);
      EXPECT_NEAR(s.surface.radius, 5.0, 1e-3);
    }
    EXPECT_EQ(belts, 1);
  }
}

// A hole of radius 1 through a plate 3 thick, sampled as sparsely as its plates: its wall is
// one ring of points half-way down between its rims (each a ring of the plates' points too).
// A sparse wall's points find their neighbours on that ring, so their normals are the ring
// plane's (given so here, as the estimator gives them on Fit4CAD's holes), and the RANSAC takes
// the ring for a plane. Its points lie on one circle, though, and the rims lie on the same
// cylinder off its plane: the wall is that cylinder, and takes its rims from the plates.
TEST(FitExactClouds, HoleSeenAsOneRingOfPointsIsACylinder) {
  Cloud c;
  testing::Draw d(23);
  const double r = 1.0, h = 3.0;
  for (const double z : {0.0, h}) {
    for (int k = 0; k < 300; ++k) {
      const double t = d.uniform(0.0, 2.0 * std::numbers::pi);
      const double rho = std::sqrt(d.uniform(1.2 * r * r, 225.0));
      c.add(Vec3(rho * std::cos(t), rho * std::sin(t), z), Vec3::UnitZ(), 0.0, d);
    }
    for (int k = 0; k < 8; ++k) {  // the rim: on the plate and on the wall
      const double t = 2.0 * std::numbers::pi * k / 8.0;
      c.add(Vec3(r * std::cos(t), r * std::sin(t), z), Vec3::UnitZ(), 0.0, d);
    }
  }
  for (int k = 0; k < 24; ++k) {  // the middle ring, with the ring plane's normal
    const double t = 2.0 * std::numbers::pi * (k + 0.5) / 24.0;
    c.add(Vec3(r * std::cos(t), r * std::sin(t), h / 2.0), Vec3::UnitZ(), 0.0, d);
  }
  RansacOptions o = derived_with_evidence(7);
  o.relabel = true;
  o.edges_to_smaller = true;
  o.probability = 0.9999;
  const auto result = detect_shapes(c.points, c.normals, o);
  ASSERT_TRUE(result.ok());
  const DetectedShape* wall = nullptr;
  for (const auto& s : result->shapes) {
    if (s.surface.type == ShapeType::Cylinder) wall = &s;
    if (s.surface.type == ShapeType::Plane) {  // the plates, no plane through the ring
      EXPECT_GT(std::abs(std::abs(s.surface.point.dot(s.surface.axis)) - h / 2.0), 1.0);
    }
  }
  ASSERT_NE(wall, nullptr);
  EXPECT_NEAR(wall->surface.radius, r, 0.01);
  EXPECT_GT(std::abs(wall->surface.axis.z()), 0.9999);
  EXPECT_EQ(wall->inliers.size(), 40U);  // the middle ring and both rims
}

// A flat face of exact points stays a plane with types by evidence (its points do not bend).
TEST(FitExactClouds, FlatFaceOfExactPointsStaysAPlane) {
  const Cloud c =
      testing::rectangle_cloud(Vec3(0, 0, 0), Vec3(2, 0, 0), Vec3(0, 4, 0.5), 0.05, 0.0, 12);
  RansacOptions o = derived_with_evidence(3);
  const auto result = detect_shapes(c.points, estimate_normals(c.points, {}), o);
  ASSERT_TRUE(result.ok());
  ASSERT_EQ(result->shapes.size(), 1U) << result->reason;
  EXPECT_EQ(result->shapes[0].surface.type, ShapeType::Plane);
  EXPECT_EQ(result->shapes[0].inliers.size(), c.points.size());
}

// A plate thinner than a neighbourhood: two exact faces 0.6 apart, points 0.5 apart, so
// every point's 16 nearest hold points of both faces. The derived noise is each face's (nil),
// not half their separation (0.3, which made epsilon 0.9 and one plane of both), so each face
// is a plane of its own points.
TEST(FitExactClouds, BothFacesOfAThinPlateAreTheirOwnPlanes) {
  Cloud c = testing::rectangle_cloud(Vec3(0, 0, 0), Vec3(10, 0, 0), Vec3(0, 10, 0), 0.5, 0.0, 1);
  c.append(testing::rectangle_cloud(Vec3(0, 0, 0.6), Vec3(10, 0, 0), Vec3(0, 10, 0), 0.5, 0.0, 2));
  const auto shapes = detect_shapes(c.points, c.normals, derived_with_evidence(3));
  ASSERT_TRUE(shapes.ok());
  EXPECT_LT(shapes->noise, 0.01);
  int faces = 0;
  for (const auto& s : shapes->shapes) {
    if (s.surface.type != ShapeType::Plane || s.inliers.size() < 200) continue;
    ++faces;
    const double z = c.points[s.inliers.front()].z();
    for (auto i : s.inliers) EXPECT_NEAR(c.points[i].z(), z, 1e-9);
  }
  EXPECT_EQ(faces, 2);
}

// Two coplanar faces with a gap of four point spacings between them: one shape at the derived
// connectivity, two at half of it; cluster_epsilon reports the scaled value.
TEST(FitExactClouds, ClusterScaleKeepsCoplanarFacesAcrossAGapApart) {
  Cloud c = testing::rectangle_cloud(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), 0.02, 0.0, 21);
  c.append(testing::rectangle_cloud(Vec3(1.08, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), 0.02, 0.0, 22));
  const auto normals = estimate_normals(c.points, {});
  RansacOptions o;
  o.epsilon = 0.005;
  o.min_points = 100;
  o.seed = 4;
  const auto joined = detect_shapes(c.points, normals, o);
  o.cluster_scale = 0.5;
  const auto apart = detect_shapes(c.points, normals, o);
  ASSERT_TRUE(joined.ok() && apart.ok());
  EXPECT_NEAR(apart->cluster_epsilon, 0.5 * joined->cluster_epsilon, 1e-12);
  ASSERT_EQ(joined->shapes.size(), 1U);
  EXPECT_EQ(joined->shapes[0].inliers.size(), c.points.size());
  ASSERT_EQ(apart->shapes.size(), 2U);
  EXPECT_EQ(apart->shapes[0].inliers.size() + apart->shapes[1].inliers.size(), c.points.size());
  for (const auto& s : apart->shapes) EXPECT_EQ(s.surface.type, ShapeType::Plane);
  o.cluster_scale = 0.0;
  EXPECT_FALSE(detect_shapes(c.points, normals, o).ok());
}

// The side of a prism over a regular 48-gon (circumradius 10, 3 high) in exact points 0.25
// apart: each face (1.31 wide) bulges 0.021 from the circle through the corners, within the
// epsilon derived from the spacing (0.025), and its normals turn at most 3.75° from the radial
// ones, so a cylinder takes every face at once. Each face is a plane its points fit exactly and
// the cylinder does not: the faces are planes.
TEST(FitExactClouds, FacesOfAPolygonalPrismArePlanesNotACylinder) {
  constexpr int kSides = 48;
  const double r = 10.0, h = 3.0;
  const double step = 2.0 * std::numbers::pi / kSides;
  Cloud c;
  for (int k = 0; k < kSides; ++k) {
    const Vec3 p(r * std::cos(k * step), r * std::sin(k * step), 0.0);
    const Vec3 q(r * std::cos((k + 1) * step), r * std::sin((k + 1) * step), 0.0);
    c.append(testing::rectangle_cloud(p, q - p, Vec3(0, 0, h), 0.25, 0.0, 40 + k));
  }
  const auto result = detect_shapes(c.points, c.normals, derived_with_evidence(7));
  ASSERT_TRUE(result.ok()) << result.error().message;
  ASSERT_GT(result->epsilon, 0.0215);  // the faces lie within a cylinder's band
  // Every shape is a plane, and each plane is a face's: the face under its points' centre, its
  // normal within a hundredth of the faces' angular step of that face's (the plane is refitted
  // to its inliers, which take the neighbours' points within epsilon of it along its edges),
  // each face's at most once.
  std::vector<int> taken(kSides, 0);
  for (const auto& s : result->shapes) {
    ASSERT_EQ(s.surface.type, ShapeType::Plane)
        << shape_type_name(s.surface.type) << " of " << s.inliers.size() << " points";
    Vec3 centre = Vec3::Zero();
    for (auto i : s.inliers) centre += c.points[i];
    const double at = std::atan2(centre.y(), centre.x());
    const int face = (static_cast<int>(std::floor(at / step)) + kSides) % kSides;
    const Vec3 normal(std::cos((face + 0.5) * step), std::sin((face + 0.5) * step), 0.0);
    EXPECT_GT(std::abs(s.surface.axis.dot(normal)), std::cos(0.01 * step)) << "face " << face;
    ++taken[static_cast<std::size_t>(face)];
  }
  int faces = 0;
  for (const int t : taken) {
    EXPECT_LE(t, 1);
    faces += t > 0 ? 1 : 0;
  }
  EXPECT_GE(faces, kSides - 2);
}

// A disc of radius 20 and height 4 around a hole of radius 5, its outer edges rounded by
// fillets of radius 1.4: the wall is a belt of a cylinder 1.2 high between two quarter tori.
// Within epsilon of the sphere through the belt's middle circle lie the belt and the fillets'
// rims, so a sphere can be found first, holding more points than the belt. After the points
// are given to the shapes they fit best, the belt's own points are exact on a cylinder: its
// type is asked again on them, and it is a cylinder.
TEST(FitExactClouds, FilletedDiscWallIsACylinderOnItsOwnPoints) {
  constexpr double kOuter = 20.0, kHole = 5.0, kHeight = 4.0, kFillet = 1.4;
  constexpr double kStep = 0.5;  // the spacing of a CAD object's sampling, in rings
  Cloud c;
  testing::Draw d(139);
  // A ring of points at radius rho and height z, with the normal `normal(angle)`; rings start
  // at a random angle, so that no two line up.
  auto ring = [&](double rho, double z, const auto& normal) {
    const int n = std::max(3, static_cast<int>(std::lround(2.0 * std::numbers::pi * rho / kStep)));
    const double start = d.uniform(0.0, 2.0 * std::numbers::pi);
    for (int k = 0; k < n; ++k) {
      const double t = start + 2.0 * std::numbers::pi * k / n;
      c.add(Vec3(rho * std::cos(t), rho * std::sin(t), z), normal(t), 0.0, d);
    }
  };
  auto up = [](double) { return Vec3::UnitZ(); };
  auto in = [](double t) { return Vec3(-std::cos(t), -std::sin(t), 0.0); };
  auto out = [](double t) { return Vec3(std::cos(t), std::sin(t), 0.0); };
  const double inner = kOuter - kFillet;
  for (double rho = kHole; rho <= inner + 1e-9; rho += kStep) {  // the two faces
    ring(rho, 0.0, up);
    ring(rho, kHeight, up);
  }
  for (double z = kStep; z < kHeight - 1e-9; z += kStep) ring(kHole, z, in);  // the hole
  // The fillets, quarter tori of tube radius kFillet, in rings along the tube.
  const int arcs = static_cast<int>(std::lround(0.5 * std::numbers::pi * kFillet / kStep));
  for (int k = 1; k < arcs; ++k) {
    const double v = 0.5 * std::numbers::pi * k / arcs;
    const double rho = inner + kFillet * std::cos(v);
    ring(rho, kFillet - kFillet * std::sin(v), [&](double t) {
      return Vec3(std::cos(v) * std::cos(t), std::cos(v) * std::sin(t), -std::sin(v));
    });
    ring(rho, kHeight - kFillet + kFillet * std::sin(v), [&](double t) {
      return Vec3(std::cos(v) * std::cos(t), std::cos(v) * std::sin(t), std::sin(v));
    });
  }
  ring(kOuter, kFillet, out);  // the circles where the fillets meet the wall
  ring(kOuter, kHeight - kFillet, out);
  const std::size_t belt_begin = c.points.size();  // the wall between them
  for (int k = 1; k < 4; ++k) ring(kOuter, kFillet + k * (kHeight - 2.0 * kFillet) / 4.0, out);
  const std::size_t belt_end = c.points.size();
  const auto normals = sharp_normals(c);
  // Rings sampled this regularly also lie on other surfaces two at a time (any two circles of
  // a fillet lie on a cone), so a draw can break a fillet into such pieces, which then hold the
  // belt; most draws do not.
  int walls = 0;
  for (const std::uint64_t seed : {1, 2, 3, 4, 5, 6, 7, 8}) {
    const auto result = detect_shapes(c.points, normals, cad_options(seed));
    ASSERT_TRUE(result.ok());
    // The shape holding most of the belt's points: a cylinder of the disc's radius, holding
    // all of them.
    std::vector<std::size_t> held(result->shapes.size(), 0);
    for (std::size_t i = belt_begin; i < belt_end; ++i) {
      if (result->assignment[i] >= 0) ++held[static_cast<std::size_t>(result->assignment[i])];
    }
    const auto most =
        static_cast<std::size_t>(std::max_element(held.begin(), held.end()) - held.begin());
    ASSERT_LT(most, result->shapes.size());
    const auto& wall = result->shapes[most].surface;
    const bool cylinder = wall.type == ShapeType::Cylinder &&
                          std::abs(wall.radius - kOuter) < 1e-3 &&
                          held[most] == belt_end - belt_begin;
    walls += cylinder ? 1 : 0;
    if (!cylinder) {
      std::printf("seed %llu: the belt's shape is a %s of %zu points holding %zu of %zu\n",
                  static_cast<unsigned long long>(seed), shape_type_name(wall.type),
                  result->shapes[most].inliers.size(), held[most], belt_end - belt_begin);
    }
  }
  EXPECT_GE(walls, 6);
}

// A tube's rounded end, as Fit4CAD's PC49: the outer wall (radius 9.525) and the bore (3.175)
// meet the end face (a ring 1.27 wide) in fillets of radius 2.54, sampled coarsely and
// exactly. Every point bends away from the plane through its neighbours, so the planes would
// say the cloud is noisy (about 0.02); the quadrics over them say it is exact, so the rules for
// exact points hold. The walls are cylinders fitted to their own points, exact, though their
// inliers reach into the fillets' rims, and the outer fillet is a torus of its own radii. (The
// bore's fillet, six points across, is not yet found whole in every draw.)
TEST(FitExactClouds, CoarseTubeEndIsExactAndItsWallsAndFilletFitTheirOwnPoints) {
  constexpr double kOuter = 9.525, kBore = 3.175, kFillet = 2.54, kTop = 19.05;
  constexpr double kDensity = 2.0;  // points per unit of area
  testing::Draw d(49);
  Cloud c;
  auto count = [&](double area) { return static_cast<int>(area * kDensity); };
  const double length = 10.0;  // of the walls below the fillets
  c.append(testing::cylinder_cloud(Vec3(0, 0, kTop - kFillet - length), Vec3::UnitZ(), kOuter,
                                   length, 0.0, 2.0 * std::numbers::pi,
                                   count(2.0 * std::numbers::pi * kOuter * length), 0.0, 50));
  c.append(testing::cylinder_cloud(Vec3(0, 0, kTop - kFillet - length), Vec3::UnitZ(), kBore,
                                   length, 0.0, 2.0 * std::numbers::pi,
                                   count(2.0 * std::numbers::pi * kBore * length), 0.0, 51));
  const double ring_in = kBore + kFillet, ring_out = kOuter - kFillet;
  for (int k = 0; k < count(std::numbers::pi * (ring_out * ring_out - ring_in * ring_in)); ++k) {
    const double t = d.uniform(0.0, 2.0 * std::numbers::pi);
    const double rho = std::sqrt(d.uniform(ring_in * ring_in, ring_out * ring_out));
    c.add(Vec3(rho * std::cos(t), rho * std::sin(t), kTop), Vec3::UnitZ(), 0.0, d);
  }
  // Quarter tori: the outer one's tube faces out and up, the bore's in and up.
  for (const double side : {1.0, -1.0}) {
    const double major = side > 0.0 ? ring_out : ring_in;
    const int n = count(0.5 * std::numbers::pi * kFillet * 2.0 * std::numbers::pi * major);
    for (int k = 0; k < n; ++k) {
      const double u = d.uniform(0.0, 2.0 * std::numbers::pi);
      const double v = d.uniform(0.0, 0.5 * std::numbers::pi);
      const Vec3 radial(std::cos(u), std::sin(u), 0.0);
      const Vec3 normal = side * std::cos(v) * radial + std::sin(v) * Vec3::UnitZ();
      c.add(Vec3(0, 0, kTop - kFillet) + major * radial + kFillet * normal, normal, 0.0, d);
    }
  }
  const auto normals = sharp_normals(c);
  for (const std::uint64_t seed : {1, 2, 3}) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const auto result = detect_shapes(c.points, normals, cad_options(seed));
    ASSERT_TRUE(result.ok());
    EXPECT_LT(result->noise, 1e-4 * result->spacing);
    // The walls: cylinders of the drawn radii.
    for (const double radius : {kOuter, kBore}) {
      bool found = false;
      for (const auto& s : result->shapes) {
        found = found || (s.surface.type == ShapeType::Cylinder &&
                          std::abs(s.surface.radius - radius) < 5e-4);
      }
      EXPECT_TRUE(found) << "no cylinder of radius " << radius;
    }
    // The outer fillet: a torus of its radii, once the wider torus over both fillets (which
    // fits neither exactly) has given its points back for a second search.
    bool fillet = false;
    for (const auto& s : result->shapes) {
      fillet = fillet || (s.surface.type == ShapeType::Torus &&
                          std::abs(s.surface.radius - ring_out) < 0.01 &&
                          std::abs(s.surface.radius2 - kFillet) < 0.01);
    }
    EXPECT_TRUE(fillet) << "no torus of the outer fillet";
  }
}

// A face continued by a fillet (a quarter cylinder of radius 2 tangent to it), exact points:
// near the tangent line the face lies within epsilon of the fillet for a band a few spacings
// wide, but on the face. A point on both goes to the smaller shape (the fillet keeps its rims);
// a point of that band is no fillet's point and stays with the face.
TEST(FitExactClouds, FaceBandTangentToAFilletStaysWithTheFace) {
  constexpr double kRadius = 2.0, kStep = 0.1;
  Cloud c;
  testing::Draw d(66);
  // The face z = 0 for x in [-12, 0], y in [0, 6] (more than twice the fillet's points); the
  // fillet bends up from x = 0 around the axis x = 0, z = 2.
  const std::size_t face = static_cast<std::size_t>(12.0 * 6.0 / (kStep * kStep));
  for (std::size_t k = 0; k < face; ++k) {
    c.add(Vec3(d.uniform(-12.0, 0.0), d.uniform(0.0, 6.0), 0.0), Vec3::UnitZ(), 0.0, d);
  }
  const auto arc = static_cast<int>(0.5 * std::numbers::pi * kRadius * 6.0 / (kStep * kStep));
  for (int k = 0; k < arc; ++k) {
    const double t = d.uniform(0.0, 0.5 * std::numbers::pi);
    const Vec3 normal(-std::sin(t), 0.0, std::cos(t));
    c.add(Vec3(kRadius * std::sin(t), d.uniform(0.0, 6.0), kRadius - kRadius * std::cos(t)), normal,
          0.0, d);
  }
  const auto normals = sharp_normals(c);
  for (const std::uint64_t seed : {1, 2, 3}) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    RansacOptions o = cad_options(seed);
    o.edges_to_smaller = true;
    const auto result = detect_shapes(c.points, normals, o);
    ASSERT_TRUE(result.ok());
    std::size_t band = 0;  // face points a spacing or more from the tangent line, on the fillet
    for (std::size_t i = 0; i < face; ++i) {
      const int a = result->assignment[i];
      if (a < 0 || c.points[i].x() > -result->spacing) continue;
      band += result->shapes[static_cast<std::size_t>(a)].surface.type == ShapeType::Cylinder;
    }
    EXPECT_EQ(band, 0u);
  }
}

// A box's corner rounded as a CAD object is (as Fit4CAD's PC18): three faces, three edges
// rounded by quarter cylinders of radius 1 and the corner by an eighth of a sphere of radius 1,
// sampled exactly, the faces finely, the rounds coarsely (`along` staggered rows of two points
// across each edge's round, seven points inside the corner's). With the fewest points of a shape
// above a round's, the search cannot see the rounds, and their free points are one connected group
// of three cylinders and a sphere; with rounds as large as a shape, the search's cylinders
// take the corner's points within epsilon and are refitted through them. Either way each round
// is found as its own exact surface: a cylinder of radius 1 along its edge, the sphere at the
// corner's centre.
TEST(FitExactClouds, ACornersRoundsAreACylinderEachAndASphere) {
  constexpr double kLength = 2.0, kStep = 0.25;
  for (const int along : {3, 8}) {
    SCOPED_TRACE(std::to_string(along) + " rows along each edge's round");
    Cloud c;
    testing::Draw d(181);
    // Points of (a, b) over [1, kLength]² of a face, (u, v, w) the axes it spans and its normal.
    auto face = [&](int u, int v, int w) {
      for (double a = 1.0; a <= kLength + 1e-9; a += kStep) {
        for (double b = 1.0; b <= kLength + 1e-9; b += kStep) {
          Vec3 p = Vec3::Zero();
          p[u] = a;
          p[v] = b;
          Vec3 n = Vec3::Zero();
          n[w] = -1.0;
          c.add(p, n, 0.0, d);
        }
      }
    };
    face(0, 1, 2);
    face(0, 2, 1);
    face(1, 2, 0);
    const std::size_t rounds_begin = c.points.size();
    // Each edge's round along axis k, from 1 to kLength.
    for (int k = 0; k < 3; ++k) {
      const int i = (k + 1) % 3, j = (k + 2) % 3;
      for (int row = 0; row < along; ++row) {
        const double t = 1.0 + (kLength - 1.0) * (row + 0.3 + 0.1 * k) / along;
        // Rows alternate their angles (a staggered sampling), two points each.
        const double first = (row + k) % 2 == 0 ? 0.35 : 0.6;
        for (const double phi : {first, first + 0.6}) {
          Vec3 p, n = Vec3::Zero();
          p[k] = t;
          p[i] = 1.0 - std::sin(phi);
          p[j] = 1.0 - std::cos(phi);
          n[i] = -std::sin(phi);
          n[j] = -std::cos(phi);
          c.add(p, n, 0.0, d);
        }
      }
    }
    const std::size_t corner_begin = c.points.size();
    for (const auto& [theta, phi] :
         {std::pair{0.6, 0.5}, std::pair{0.9, 1.1}, std::pair{1.2, 0.3}, std::pair{0.4, 1.3},
          std::pair{1.1, 0.8}, std::pair{0.3, 0.2}, std::pair{1.4, 1.0}}) {
      const Vec3 n(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi),
                   std::cos(theta));
      c.add(Vec3(1, 1, 1) - n, -n, 0.0, d);
    }
    const std::size_t corner_end = c.points.size();
    RansacOptions o = cad_options(3);
    o.min_points = 8;
    const auto result = detect_shapes(c.points, sharp_normals(c), o);
    ASSERT_TRUE(result.ok()) << result.error().message;
    // The shape holding most of each round's points, and what it is.
    auto holder = [&](std::size_t begin, std::size_t end) -> const DetectedShape* {
      std::vector<std::size_t> held(result->shapes.size(), 0);
      for (std::size_t p = begin; p < end; ++p) {
        if (result->assignment[p] >= 0) ++held[static_cast<std::size_t>(result->assignment[p])];
      }
      if (held.empty()) return nullptr;
      const auto most = std::max_element(held.begin(), held.end()) - held.begin();
      return held[static_cast<std::size_t>(most)] * 2 > end - begin
                 ? &result->shapes[static_cast<std::size_t>(most)]
                 : nullptr;
    };
    for (int k = 0; k < 3; ++k) {
      SCOPED_TRACE("the round along axis " + std::to_string(k));
      const std::size_t begin = rounds_begin + static_cast<std::size_t>(2 * along * k);
      const DetectedShape* round = holder(begin, begin + static_cast<std::size_t>(2 * along));
      ASSERT_NE(round, nullptr);
      ASSERT_EQ(round->surface.type, ShapeType::Cylinder);
      EXPECT_NEAR(round->surface.radius, 1.0, 1e-6);
      EXPECT_GT(std::abs(round->surface.axis[k]), 1.0 - 1e-9);
    }
    const DetectedShape* corner = holder(corner_begin, corner_end);
    ASSERT_NE(corner, nullptr);
    ASSERT_EQ(corner->surface.type, ShapeType::Sphere);
    EXPECT_NEAR(corner->surface.radius, 1.0, 1e-6);
    EXPECT_LT((corner->surface.point - Vec3(1, 1, 1)).norm(), 1e-6);
  }
}

// A flat strip between two arcs of radius 5 (as Fit4CAD's PC109), sampled exactly in columns
// half a unit apart: its two edge columns are the arcs' last, its one inner column is free (too
// few points for a shape, 0.025 off the arcs, on one line). The plane through it and the rims
// beside it (three columns: not two lines, which any plane through two columns would be) is a
// shape holding the inner column.
TEST(FitExactClouds, AFlatStripBetweenTwoArcsIsAPlaneThroughItsRims) {
  Cloud c;
  testing::Draw d(109);
  auto column = [&](const Vec3& at, const Vec3& normal) {
    for (int row = 0; row <= 8; ++row) c.add(at + Vec3(0, 0, 0.5 * row), normal, 0.0, d);
  };
  const double r = 5.0, step = 0.1;  // 0.5 along the arc
  for (int k = 15; k >= 0; --k) {    // arc A about (0, 0), up to 90 degrees
    const double a = std::numbers::pi / 2.0 - k * step;
    column(Vec3(r * std::cos(a), r * std::sin(a), 0), Vec3(std::cos(a), std::sin(a), 0));
  }
  const std::size_t inner = c.points.size();
  column(Vec3(-0.5, r, 0), Vec3::UnitY());  // the strip's inner column
  for (int k = 0; k <= 15; ++k) {           // arc B about (-1, 0), from 90 to 180 degrees
    const double a = std::numbers::pi / 2.0 + k * step;
    column(Vec3(-1.0 + r * std::cos(a), r * std::sin(a), 0), Vec3(std::cos(a), std::sin(a), 0));
  }
  RansacOptions o = cad_options(5);
  o.min_points = 30;
  const auto result = detect_shapes(c.points, sharp_normals(c), o);
  ASSERT_TRUE(result.ok()) << result.error().message;
  const int s = result->assignment[inner];
  ASSERT_GE(s, 0);
  const DetectedShape& strip = result->shapes[static_cast<std::size_t>(s)];
  EXPECT_EQ(strip.surface.type, ShapeType::Plane);
  EXPECT_GT(std::abs(strip.surface.axis.y()), 1.0 - 1e-9);
  for (std::size_t k = inner; k < inner + 9; ++k) EXPECT_EQ(result->assignment[k], s);
}

}  // namespace
}  // namespace csgtile::fit
