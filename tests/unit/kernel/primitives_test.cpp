// Builders: topology counts, validity and closed-form mass properties of every primitive.

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "csgtile/kernel/check.h"
#include "csgtile/kernel/explorer.h"
#include "csgtile/kernel/mass_properties.h"
#include "csgtile/kernel/primitives.h"

namespace csgtile::kernel {
namespace {

constexpr double kPi = std::numbers::pi;

struct Counts {
  std::size_t solids, shells, faces, wires, edges, vertices;
};

struct PrimitiveCase {
  const char* name;
  Result<Shape> (*build)();
  Counts counts;
  double volume, area;
  Vec3 centroid;
};

Counts counts_of(const Shape& s) {
  const auto c = count_shapes(s);
  auto n = [&](ShapeKind k) { return c[static_cast<int>(k)]; };
  return {n(ShapeKind::Solid), n(ShapeKind::Shell), n(ShapeKind::Face),
          n(ShapeKind::Wire),  n(ShapeKind::Edge),  n(ShapeKind::Vertex)};
}

// Frustum r1=2, r2=1, h=3: V = πh/3 (r1² + r1 r2 + r2²), lateral = π (r1 + r2) √(h² + (r1-r2)²).
const double kFrustumVolume = kPi * 3 / 3 * (4 + 2 + 1);
const double kFrustumArea = kPi * 4 + kPi * 1 + kPi * 3 * std::sqrt(9 + 1);
const double kFrustumCentroidZ = 3 * (4 + 2 * 2 + 3 * 1) / (4.0 * (4 + 2 + 1));
// Cone r=2, h=3 apex up.
const double kConeArea = kPi * 4 + kPi * 2 * std::sqrt(9 + 4);
// Revolution of the unit-ish trapezoid profile (1,0),(3,0),(2,2),(1,2): Pappus: V = 2π·A·ρ̄.
const double kTrapezoidArea = 0.5 * (2 + 1) * 2;
const double kTrapezoidRhoBar =
    (  // centroid rho of the trapezoid: square [1,2]x[0,2] + triangle (2,0),(3,0),(2,2)
        2.0 * 1.5 + 1.0 * (7.0 / 3)) /
    kTrapezoidArea;

const PrimitiveCase kCases[] = {
    {"box", [] { return make_box(1, 2, 3); }, {1, 1, 6, 6, 12, 8}, 6, 22, {0.5, 1, 1.5}},
    {"cylinder",
     [] { return make_cylinder(2, 3); },
     {1, 1, 3, 3, 3, 2},
     kPi * 12,
     2 * kPi * 4 + 2 * kPi * 2 * 3,
     {0, 0, 1.5}},
    {"frustum",
     [] { return make_cone(2, 1, 3); },
     {1, 1, 3, 3, 3, 2},
     kFrustumVolume,
     kFrustumArea,
     {0, 0, kFrustumCentroidZ}},
    {"cone_apex_up",
     [] { return make_cone(2, 0, 3); },
     {1, 1, 2, 2, 3, 2},
     kPi * 4,
     kConeArea,
     {0, 0, 0.75}},
    {"cone_apex_down",
     [] { return make_cone(0, 2, 3); },
     {1, 1, 2, 2, 3, 2},
     kPi * 4,
     kConeArea,
     {0, 0, 2.25}},
    {"sphere",
     [] { return make_sphere(2); },
     {1, 1, 1, 1, 3, 2},
     4.0 / 3 * kPi * 8,
     4 * kPi * 4,
     {0, 0, 0}},
    {"torus",
     [] { return make_torus(3, 1); },
     {1, 1, 1, 1, 2, 1},
     2 * kPi* kPi * 3,
     4 * kPi* kPi * 3,
     {0, 0, 0}},
    {"extrusion_L_with_hole",
     [] {
       return make_extrusion({{0, 0}, {4, 0}, {4, 1}, {1, 1}, {1, 4}, {0, 4}}, {}, 2);
     },
     {1, 1, 8, 8, 18, 12},
     14,
     2 * 7 + 2 * 16,
     {0, 0, 0}},
    {"extrusion_square_hole",
     [] {
       return make_extrusion({{0, 0}, {4, 0}, {4, 4}, {0, 4}}, {{{1, 1}, {1, 2}, {2, 2}, {2, 1}}},
                             2);
     },
     {1, 1, 10, 12, 24, 16},
     30,
     2 * 15 + 2 * 16 + 2 * 4,
     {0, 0, 0}},
    {"revolution_trapezoid",
     [] {
       return make_revolution({{1, 0}, {3, 0}, {2, 2}, {1, 2}}, 2 * kPi);
     },
     {1, 1, 4, 6, 6, 4},
     2 * kPi* kTrapezoidArea* kTrapezoidRhoBar,
     0,
     {0, 0, 0}},
    {"revolution_quarter_box",
     [] {
       return make_revolution({{0, 0}, {2, 0}, {2, 1}, {0, 1}}, kPi / 2);
     },
     {1, 1, 5, 5, 9, 6},
     kPi / 4 * 4,
     2 * 2 + kPi + 2 * kPi,
     {0, 0, 0}},
};

class Primitive : public ::testing::TestWithParam<PrimitiveCase> {};

TEST_P(Primitive, IsValidWithDocumentedCountsAndClosedFormMassProperties) {
  const PrimitiveCase& c = GetParam();
  auto built = c.build();
  ASSERT_TRUE(built.ok()) << built.error().message;
  const Shape& s = built.value();
  const CheckReport report = check_shape(s);
  for (const auto& issue : report.issues)
    ADD_FAILURE() << check_status_name(issue.status) << ": " << issue.message;
  const Counts n = counts_of(s);
  EXPECT_EQ(n.solids, c.counts.solids);
  EXPECT_EQ(n.shells, c.counts.shells);
  EXPECT_EQ(n.faces, c.counts.faces);
  EXPECT_EQ(n.wires, c.counts.wires);
  EXPECT_EQ(n.edges, c.counts.edges);
  EXPECT_EQ(n.vertices, c.counts.vertices);
  const MassProperties mp = mass_properties(s);
  EXPECT_NEAR(mp.volume, c.volume, 1e-12 * c.volume);
  if (c.area > 0) {
    EXPECT_NEAR(mp.area, c.area, 1e-12 * c.area);
  }
  if (c.centroid != Vec3::Zero()) {
    EXPECT_LT((mp.centroid - c.centroid).norm(), 1e-12);
  }
}

INSTANTIATE_TEST_SUITE_P(AllTypes, Primitive, ::testing::ValuesIn(kCases),
                         [](const auto& param_info) { return std::string(param_info.param.name); });

TEST(Primitive, ExactBoundingBoxes) {
  auto box_of = [](Result<Shape> s) { return bounding_box(s.value()); };
  BoundingBox torus = box_of(make_torus(3, 1));
  EXPECT_TRUE(torus.min.isApprox(Vec3(-4, -4, -1), 1e-14));
  EXPECT_TRUE(torus.max.isApprox(Vec3(4, 4, 1), 1e-14));
  BoundingBox sphere = box_of(make_sphere(2));
  EXPECT_TRUE(sphere.min.isApprox(Vec3(-2, -2, -2), 1e-14));
  BoundingBox quarter = box_of(make_revolution({{0, 0}, {2, 0}, {2, 1}, {0, 1}}, kPi / 2));
  EXPECT_NEAR(quarter.min.x(), 0, 1e-14);
  EXPECT_NEAR(quarter.max.y(), 2, 1e-14);
}

// A scaled placement scales the box: a line edge's parameter is arc length in its body, so
// under a location of scale s it runs over s times that range on the moved line.
TEST(Primitive, BoundingBoxUnderAScaledPlacement) {
  for (const double s : {0.5, 2.0}) {
    const Shape box = make_box(1, 2, 3).value().moved(Location::scaling(s));
    const BoundingBox b = bounding_box(box);
    EXPECT_LT(b.min.norm(), 1e-14) << s << ": " << b.min.transpose();
    EXPECT_TRUE(b.max.isApprox(Vec3(s, 2 * s, 3 * s), 1e-14)) << s << ": " << b.max.transpose();
  }
}

TEST(Primitive, RejectsBadParametersWithNamedErrors) {
  EXPECT_EQ(make_box(0, 1, 1).error().code, ErrorCode::InvalidArgument);
  EXPECT_EQ(make_cylinder(-1, 1).error().code, ErrorCode::InvalidArgument);
  EXPECT_EQ(make_cone(0, 0, 1).error().code, ErrorCode::InvalidArgument);
  EXPECT_EQ(make_torus(1, 2).error().code, ErrorCode::InvalidArgument);
  EXPECT_EQ(make_sphere(NAN).error().code, ErrorCode::InvalidArgument);
  auto bowtie = make_extrusion({{0, 0}, {3, 0}, {0, 2}, {1, 3}}, {}, 1);
  ASSERT_FALSE(bowtie.ok());
  EXPECT_EQ(bowtie.error().code, ErrorCode::DegenerateGeometry);
  EXPECT_NE(bowtie.error().message.find("intersects itself"), std::string::npos);
  auto collinear = make_extrusion({{0, 0}, {1, 0}, {2, 0}}, {}, 1);
  EXPECT_EQ(collinear.error().code, ErrorCode::DegenerateGeometry);
  auto outside_hole =
      make_extrusion({{0, 0}, {1, 0}, {1, 1}, {0, 1}}, {{{2, 2}, {3, 2}, {3, 3}}}, 1);
  EXPECT_EQ(outside_hole.error().code, ErrorCode::DegenerateGeometry);
  auto crossing_axis = make_revolution({{-1, 0}, {1, 0}, {1, 1}}, kPi);
  EXPECT_EQ(crossing_axis.error().code, ErrorCode::DegenerateGeometry);
  EXPECT_EQ(make_revolution({{1, 0}, {2, 0}, {2, 1}}, 7.0).error().code,
            ErrorCode::InvalidArgument);
}

TEST(Primitive, ProfileOrientationDoesNotMatter) {
  auto ccw = make_revolution({{1, 0}, {2, 0}, {2, 1}, {1, 1}}, kPi);
  auto cw = make_revolution({{1, 1}, {2, 1}, {2, 0}, {1, 0}}, kPi);
  ASSERT_TRUE(ccw.ok() && cw.ok());
  EXPECT_NEAR(mass_properties(ccw.value()).volume, mass_properties(cw.value()).volume, 1e-12);
  EXPECT_TRUE(check_shape(cw.value()).valid());
}

TEST(Primitive, BuildPrimitiveAppliesThePlacement) {
  PrimitiveSpec spec;
  spec.type = PrimitiveType::Cylinder;
  spec.radius = 1;
  spec.height = 2;
  spec.placement = Location::translation(Vec3(10, 0, 0)) *
                   Location::rotation(Vec3::Zero(), Vec3::UnitX(), kPi / 2) *
                   Location::scaling(2.0);
  auto s = build_primitive(spec);
  ASSERT_TRUE(s.ok());
  const MassProperties mp = mass_properties(s.value());
  EXPECT_NEAR(mp.volume, kPi * 2 * 8, 1e-12 * mp.volume);
  EXPECT_TRUE(mp.centroid.isApprox(Vec3(10, -2, 0), 1e-12));
  EXPECT_TRUE(check_shape(s.value()).valid());
}

// A building's roof part: the extrusion of its outline cut by the half-space under its roof
// plane — here an L-shaped outline under one slope, z = 6 + 0.5 x (clip n·p <= d with
// n ∝ (-0.5, 0, 1), d = 6 / |(-0.5, 0, 1)|). Volume: each rectangle's area times the mean
// height over it.
TEST(Primitive, ClipsCutTheSolidByTheirHalfSpaces) {
  PrimitiveSpec spec;
  spec.type = PrimitiveType::Extrusion;
  spec.profile = {{0, 0}, {8, 0}, {8, 4}, {4, 4}, {4, 10}, {0, 10}};
  spec.height = 20.0;
  const Vec3 n = Vec3(-0.5, 0.0, 1.0).normalized();
  spec.clips.push_back(Eigen::Vector4d(n.x(), n.y(), n.z(), 6.0 * n.z()));
  spec.placement = Location::translation(Vec3(85000.0, 446000.0, -1.0));
  const auto solid = build_primitive(spec);
  ASSERT_TRUE(solid.ok()) << solid.error().message;
  EXPECT_TRUE(check_shape(solid.value()).valid());
  // [0,8]×[0,4]: mean height 6 + 0.5·4 = 8; [0,4]×[4,10]: 6 + 0.5·2 = 7.
  EXPECT_NEAR(mass_properties(solid.value()).volume, 32.0 * 8.0 + 24.0 * 7.0, 1e-6);
  EXPECT_EQ(map_child_shapes(solid.value(), ShapeKind::Face).size(), 8u);  // 6 walls, floor, roof
  // A plane above the solid changes nothing; one below it, or a bad normal, is an error.
  PrimitiveSpec above = spec;
  above.clips = {Eigen::Vector4d(0, 0, 1, 50.0)};
  EXPECT_NEAR(mass_properties(build_primitive(above).value()).volume, 56.0 * 20.0, 1e-6);
  PrimitiveSpec below = spec;
  below.clips = {Eigen::Vector4d(0, 0, 1, -1.0)};
  EXPECT_EQ(build_primitive(below).error().code, ErrorCode::DegenerateGeometry);
  PrimitiveSpec bad = spec;
  bad.clips = {Eigen::Vector4d(0, 0, 2, 1.0)};
  EXPECT_EQ(build_primitive(bad).error().code, ErrorCode::DegenerateGeometry);
}

// A clipped solid is remembered by its local spec: a second build at another placement is the
// first one's solid moved (the same body, the same faces and volume), and a spec that differs
// in one clip is built anew; a remembered error is the same error.
TEST(Primitive, ClippedSolidsAreRememberedByTheirLocalSpec) {
  PrimitiveSpec spec;
  spec.type = PrimitiveType::Extrusion;
  spec.profile = {{0, 0}, {6, 0}, {6, 5}, {0, 5}};
  spec.height = 12.0;
  const Vec3 n = Vec3(0.0, -0.4, 1.0).normalized();
  spec.clips.push_back(Eigen::Vector4d(n.x(), n.y(), n.z(), 7.0 * n.z()));
  spec.placement = Location::translation(Vec3(10.0, 0.0, 0.0));
  const auto first = build_primitive(spec);
  ASSERT_TRUE(first.ok()) << first.error().message;
  PrimitiveSpec moved = spec;
  moved.placement = Location::translation(Vec3(-3.0, 40.0, 2.0));
  const auto second = build_primitive(moved);
  ASSERT_TRUE(second.ok()) << second.error().message;
  EXPECT_TRUE(first.value().shares_body(second.value()));  // one body, two locations
  EXPECT_FALSE(first.value().is_same(second.value()));
  EXPECT_NEAR(mass_properties(second.value()).volume, mass_properties(first.value()).volume, 1e-9);
  EXPECT_TRUE(check_shape(second.value()).valid());
  // [0,6]×[0,5] under z = 7 + 0.4·y: mean height 7 + 0.4·2.5 = 8.
  EXPECT_NEAR(mass_properties(second.value()).volume, 30.0 * 8.0, 1e-6);

  PrimitiveSpec other = spec;
  other.clips[0].w() += 1.0 * n.z();  // one metre higher: another solid
  const auto third = build_primitive(other);
  ASSERT_TRUE(third.ok()) << third.error().message;
  EXPECT_FALSE(third.value().shares_body(first.value()));
  EXPECT_NEAR(mass_properties(third.value()).volume, 30.0 * 9.0, 1e-6);

  PrimitiveSpec below = spec;
  below.clips = {Eigen::Vector4d(0, 0, 1, -1.0)};
  const auto error = build_primitive(below);
  const auto again = build_primitive(below);
  ASSERT_FALSE(error.ok());
  ASSERT_FALSE(again.ok());
  EXPECT_EQ(again.error().code, error.error().code);
  EXPECT_EQ(again.error().message, error.error().message);
}

}  // namespace
}  // namespace csgtile::kernel
