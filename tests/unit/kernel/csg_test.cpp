// CSG history: trees over primitive leaves, face sources composed through Booleans, and
// their native-format section. Sources are checked geometrically: every result face lies on
// the surface of each primitive face it names.

#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>

#include "csgtile/geo/scene.h"
#include "csgtile/kernel/check.h"
#include "csgtile/kernel/csg.h"
#include "csgtile/kernel/explorer.h"
#include "csgtile/kernel/mass_properties.h"
#include "csgtile/kernel/native_format.h"
#include "csgtile/kernel/tessellation.h"
#include "test_support.h"

namespace csgtile::kernel {
namespace {

PrimitiveSpec box_at(const Vec3& size, const Vec3& at) {
  PrimitiveSpec p;
  p.type = PrimitiveType::Box;
  p.size = size;
  p.placement = Location::translation(at);
  return p;
}

CsgModel leaf(const PrimitiveSpec& spec, const std::string& label = {}) {
  auto m = csg_primitive(spec, label);
  EXPECT_TRUE(m.ok()) << m.error().message;
  return m.value();
}

SurfacePtr world_surface(const Shape& face) {
  return face.body().face()->surface->transformed(face.location());
}

double distance_to(const Surface& s, const Vec3& p) {
  const Vec2 uv = s.closest_parameters(p);
  return (s.point(uv.x(), uv.y()) - p).norm();
}

// Every face of the model lies on the surface of each of its sources: triangle centroids of
// a fine mesh are as close to the source surface as to the face's own surface.
void expect_sources_on_surfaces(const CsgModel& m) {
  ASSERT_TRUE(check_csg(m).ok()) << check_csg(m).error().message;
  const ShapeIndex faces = map_child_shapes(m.shape, ShapeKind::Face);
  std::vector<std::vector<SurfacePtr>> primitive_faces(m.nodes.size());
  for (std::size_t i = 0; i < m.nodes.size(); ++i) {
    if (m.nodes[i].kind != CsgNodeKind::Primitive) continue;
    const Shape solid = build_primitive(m.nodes[i].primitive).value();
    const ShapeIndex solid_faces = map_child_shapes(solid, ShapeKind::Face);
    for (const Shape& f : solid_faces.shapes()) {
      primitive_faces[i].push_back(world_surface(f));
    }
  }
  TessellationOptions options;
  options.chordal_tolerance = 1e-3;
  auto mesh = tessellate(m.shape, options);
  ASSERT_TRUE(mesh.ok()) << mesh.error().message;
  for (std::size_t t = 0; t < mesh->triangles.size(); ++t) {
    const auto& tri = mesh->triangles[t];
    const Vec3 c = (mesh->vertices[tri[0]] + mesh->vertices[tri[1]] + mesh->vertices[tri[2]]) / 3;
    const std::size_t f = mesh->triangle_face[t];
    const double own = distance_to(*world_surface(faces[f]), c);
    for (const FaceSource& s : m.face_sources[f]) {
      const double d = distance_to(
          *primitive_faces[static_cast<std::size_t>(s.node)][static_cast<std::size_t>(s.face)], c);
      EXPECT_LE(d, own + 1e-6) << "face " << f << " source (" << s.node << ", " << s.face << ")";
    }
  }
}

TEST(Csg, PrimitiveLeafIsItsOwnSource) {
  PrimitiveSpec cyl;
  cyl.type = PrimitiveType::Cylinder;
  cyl.radius = 1;
  cyl.height = 2;
  const CsgModel m = leaf(cyl, "column");
  ASSERT_EQ(m.nodes.size(), 1u);
  EXPECT_EQ(m.nodes[0].label, "column");
  ASSERT_EQ(m.face_sources.size(), 3u);
  for (int i = 0; i < 3; ++i) EXPECT_EQ(m.face_sources[i], (std::vector<FaceSource>{{0, i}}));
  expect_sources_on_surfaces(m);
}

TEST(Csg, FusedFaceSharingBoxesMergeTheirTopFacesSources) {
  const CsgModel a = leaf(box_at({1, 1, 1}, {0, 0, 0}), "a");
  const CsgModel b = leaf(box_at({1, 1, 1}, {1, 0, 0}), "b");
  auto r = csg_boolean(a, b, BooleanOp::Fuse);
  ASSERT_TRUE(r.ok()) << r.error().message;
  ASSERT_EQ(r->nodes.size(), 3u);
  EXPECT_EQ(r->nodes[2].kind, CsgNodeKind::Fuse);
  EXPECT_EQ(r->nodes[2].children, (std::vector<int>{0, 1}));
  ASSERT_EQ(r->face_sources.size(), 6u);
  int merged = 0, single = 0;
  for (const auto& list : r->face_sources) {
    if (list.size() == 2) {
      ++merged;
      EXPECT_EQ(list[0].node, 0);
      EXPECT_EQ(list[1].node, 1);
    } else {
      ++single;
    }
  }
  EXPECT_EQ(merged, 4);  // top, bottom, front, back: one face each from both boxes
  EXPECT_EQ(single, 2);  // the two end faces
  expect_sources_on_surfaces(r.value());
}

TEST(Csg, HoleFaceComesFromTheCylinder) {
  const CsgModel block = leaf(box_at({4, 4, 1}, {-2, -2, 0}));
  PrimitiveSpec drill;
  drill.type = PrimitiveType::Cylinder;
  drill.radius = 1;
  drill.height = 3;
  drill.placement = Location::translation({0, 0, -1});
  auto r = csg_boolean(block, leaf(drill), BooleanOp::Cut);
  ASSERT_TRUE(r.ok()) << r.error().message;
  EXPECT_EQ(r->nodes.back().kind, CsgNodeKind::Cut);
  const ShapeIndex faces = map_child_shapes(r->shape, ShapeKind::Face);
  int from_cylinder = 0;
  for (std::size_t f = 0; f < faces.size(); ++f) {
    for (const FaceSource& s : r->face_sources[f]) {
      if (s.node == 1) {
        ++from_cylinder;
        EXPECT_EQ(world_surface(faces[f])->kind(), SurfaceKind::Cylinder);
      }
    }
  }
  EXPECT_EQ(from_cylinder, 1);
  expect_sources_on_surfaces(r.value());
}

TEST(Csg, NestedOperationsComposeSources) {
  const CsgModel a = leaf(box_at({2, 2, 2}, {0, 0, 0}));
  const CsgModel b = leaf(box_at({2, 2, 2}, {1, 1, 1}));
  PrimitiveSpec ball;  // a vertical bore through the corner where the boxes overlap
  ball.type = PrimitiveType::Cylinder;
  ball.radius = 0.4;
  ball.height = 5;
  ball.placement = Location::translation({1.5, 1.5, -1});
  auto ab = csg_boolean(a, b, BooleanOp::Fuse);
  ASSERT_TRUE(ab.ok());
  auto r = csg_boolean(ab.value(), leaf(ball), BooleanOp::Cut);
  ASSERT_TRUE(r.ok()) << r.error().message;
  ASSERT_EQ(r->nodes.size(), 5u);
  EXPECT_EQ(r->nodes[2].children, (std::vector<int>{0, 1}));
  EXPECT_EQ(r->nodes[4].children, (std::vector<int>{2, 3}));
  expect_sources_on_surfaces(r.value());
}

TEST(Csg, CombineRecordsOneNaryNodeAndPassesUntouchedSolidsThrough) {
  std::vector<CsgModel> parts;
  for (int i = 0; i < 3; ++i) parts.push_back(leaf(box_at({1, 1, 1}, {0.5 * i, 0, 0})));
  parts.push_back(leaf(box_at({1, 1, 1}, {10, 0, 0})));  // touches nothing
  auto r = csg_combine(parts, BooleanOp::Fuse);
  ASSERT_TRUE(r.ok()) << r.error().message;
  ASSERT_EQ(r->nodes.size(), 5u);
  EXPECT_EQ(r->nodes.back().children, (std::vector<int>{0, 1, 2, 3}));
  EXPECT_EQ(map_child_shapes(r->shape, ShapeKind::Solid).size(), 2u);
  expect_sources_on_surfaces(r.value());
  // The lone box keeps its faces: each names node 3 only.
  int lone = 0;
  for (const auto& list : r->face_sources) lone += list.size() == 1 && list[0].node == 3;
  EXPECT_EQ(lone, 6);
}

// A model whose shape is a set of overlapping solids (a plain scene, a stacked model) is
// taken as their union: the result is valid, its volume right, and every face's sources lie
// on its surface.
TEST(Csg, SetOfOverlappingSolidsIsTakenAsTheirUnion) {
  const CsgModel a = leaf(box_at({2, 2, 2}, {0, 0, 0}), "a");
  const CsgModel b = leaf(box_at({2, 2, 2}, {1, 0, 0}), "b");
  CsgModel set;
  set.shape = ShapeFactory::compound({a.shape, b.shape}).value();
  CsgNode root;  // as assembly's stacked models: a fuse node over parts left unfused
  root.kind = CsgNodeKind::Fuse;
  root.children = {0, 1};
  set.nodes = {a.nodes[0], b.nodes[0], root};
  for (int i = 0; i < 6; ++i) set.face_sources.push_back({FaceSource{0, i}});
  for (int i = 0; i < 6; ++i) set.face_sources.push_back({FaceSource{1, i}});
  ASSERT_EQ(map_child_shapes(set.shape, ShapeKind::Face).size(), 12u);
  const CsgModel cap = leaf(box_at({3, 2, 1}, {0, 0, 2}), "cap");
  auto r = csg_boolean(set, cap, BooleanOp::Fuse);
  ASSERT_TRUE(r.ok()) << r.error().message;
  EXPECT_TRUE(check_shape(r->shape).valid());
  EXPECT_NEAR(mass_properties(r->shape).volume, 12.0 + 6.0, 1e-9);
  expect_sources_on_surfaces(r.value());
}

TEST(Csg, CheckFindsBrokenHistories) {
  auto r = csg_boolean(leaf(box_at({1, 1, 1}, {0, 0, 0})), leaf(box_at({1, 1, 1}, {0.5, 0.5, 0})),
                       BooleanOp::Common);
  ASSERT_TRUE(r.ok());
  ASSERT_TRUE(check_csg(r.value()).ok());
  {
    CsgModel m = r.value();
    m.face_sources.pop_back();
    EXPECT_FALSE(check_csg(m).ok());
  }
  {
    CsgModel m = r.value();
    m.face_sources[0] = {{0, 99}};
    EXPECT_FALSE(check_csg(m).ok());
  }
  {
    CsgModel m = r.value();
    m.face_sources[0] = {{2, 0}};  // the operation node, not a primitive
    EXPECT_FALSE(check_csg(m).ok());
  }
  {
    CsgModel m = r.value();
    m.nodes.back().children = {0, 0};
    EXPECT_FALSE(check_csg(m).ok());
  }
}

TEST(CsgNative, RoundTripKeepsTreeSourcesAndBytes) {
  PrimitiveSpec rev;
  rev.type = PrimitiveType::Revolution;
  rev.profile = {{0, 0}, {1, 0}, {1, 1}, {0.5, 2}, {0, 2}};
  rev.placement = Location::from_parts(Eigen::Matrix3d::Identity(), 1.5, Vec3(0.25, 0, 0)).value();
  PrimitiveSpec ext;
  ext.type = PrimitiveType::Extrusion;
  ext.profile = {{-2, -2}, {2, -2}, {2, 2}, {-2, 2}};
  ext.holes = {{{-0.5, -0.5}, {-0.5, 0.5}, {0.5, 0.5}, {0.5, -0.5}}};
  ext.height = 0.5;
  auto r = csg_boolean(leaf(ext, "slab"), leaf(rev, "vase"), BooleanOp::Fuse);
  ASSERT_TRUE(r.ok()) << r.error().message;
  const std::string bytes = write_native_model(r.value());
  auto back = read_native_model(bytes);
  ASSERT_TRUE(back.ok()) << back.error().message;
  EXPECT_TRUE(structurally_equal(back->shape, r->shape));
  EXPECT_EQ(back->face_sources, r->face_sources);
  ASSERT_EQ(back->nodes.size(), r->nodes.size());
  for (std::size_t i = 0; i < r->nodes.size(); ++i) {
    EXPECT_EQ(back->nodes[i].kind, r->nodes[i].kind);
    EXPECT_EQ(back->nodes[i].label, r->nodes[i].label);
    EXPECT_EQ(back->nodes[i].children, r->nodes[i].children);
    EXPECT_EQ(back->nodes[i].primitive.profile, r->nodes[i].primitive.profile);
    EXPECT_EQ(back->nodes[i].primitive.holes, r->nodes[i].primitive.holes);
    EXPECT_EQ(back->nodes[i].primitive.placement.matrix(),
              r->nodes[i].primitive.placement.matrix());
  }
  EXPECT_EQ(write_native_model(back.value()), bytes);
  // Shape-only readers skip the optional section; shape-only files have no history.
  auto shape = read_native(bytes);
  ASSERT_TRUE(shape.ok()) << shape.error().message;
  EXPECT_TRUE(structurally_equal(shape.value(), r->shape));
  auto plain = read_native_model(write_native(r->shape));
  ASSERT_TRUE(plain.ok());
  EXPECT_TRUE(plain->nodes.empty());
}

// A clipped leaf (a building's roof part) keeps its clips through the native format and the
// scene format, bit for bit; its history names the leaf for the roof face too.
TEST(CsgNative, ClippedPrimitiveRoundTrips) {
  PrimitiveSpec part;
  part.type = PrimitiveType::Extrusion;
  part.profile = {{0, 0}, {6, 0}, {6, 5}, {0, 5}};
  part.height = 15.0;
  const Vec3 n = Vec3(0.0, -0.6, 1.0).normalized();
  part.clips.push_back(Eigen::Vector4d(n.x(), n.y(), n.z(), 7.0 * n.z()));
  auto leaf = csg_primitive(part, "roof part");
  ASSERT_TRUE(leaf.ok()) << leaf.error().message;
  EXPECT_TRUE(check_csg(leaf.value()).ok());
  const std::string bytes = write_native_model(leaf.value());
  auto back = read_native_model(bytes);
  ASSERT_TRUE(back.ok()) << back.error().message;
  ASSERT_EQ(back->nodes.size(), 1u);
  EXPECT_EQ(back->nodes[0].primitive.clips, part.clips);
  EXPECT_EQ(write_native_model(back.value()), bytes);
  geo::Scene scene;
  scene.primitives.push_back({part, "p", std::nullopt});
  auto parsed = geo::parse_scene(geo::scene_to_json(scene));
  ASSERT_TRUE(parsed.ok()) << parsed.error().message;
  EXPECT_EQ(parsed->primitives[0].spec.clips, part.clips);
  // A plain leaf is written as before (no clip bit).
  PrimitiveSpec plain = part;
  plain.clips.clear();
  const std::string plain_bytes = write_native_model(csg_primitive(plain).value());
  EXPECT_TRUE(read_native_model(plain_bytes).ok());
  EXPECT_TRUE(read_native_model(plain_bytes)->nodes[0].primitive.clips.empty());
}

TEST(CsgNative, DamagedSectionsAreRefusedByName) {
  auto r = csg_boolean(leaf(box_at({1, 1, 1}, {0, 0, 0})), leaf(box_at({1, 1, 1}, {0.5, 0, 0})),
                       BooleanOp::Fuse);
  ASSERT_TRUE(r.ok());
  // A history that does not fit the shape is written as given but refused on reading.
  CsgModel wrong = r.value();
  wrong.face_sources.pop_back();
  auto back = read_native_model(write_native_model(wrong));
  ASSERT_FALSE(back.ok());
  EXPECT_EQ(back.error().code, ErrorCode::CorruptData);
  EXPECT_NE(back.error().message.find("face source lists"), std::string::npos);
  // Every truncation of the file is refused cleanly.
  const std::string bytes = write_native_model(r.value());
  for (std::size_t n = 0; n < bytes.size(); n += 7) {
    EXPECT_FALSE(read_native_model(bytes.substr(0, n)).ok()) << n;
  }
}

// The closed-form cases of ../shared/cases through csg_combine: volumes as boolean_fold's,
// every face's sources on its surface, and the history surviving the native round trip.
TEST(CsgSharedCases, HistoryOfEveryCase) {
  const auto dir = test::shared_dir() / "cases";
  if (!std::filesystem::exists(dir / "cases.json")) GTEST_SKIP() << dir << " is absent";
  const auto index = nlohmann::json::parse(test::read_file(dir / "cases.json"));
  int cases = 0;
  for (const auto& c : index["cases"]) {
    const std::string name = c["name"].get<std::string>();
    SCOPED_TRACE(name);
    auto scene = geo::read_scene(dir / (name + ".json"));
    ASSERT_TRUE(scene.ok()) << scene.error().message;
    std::vector<CsgModel> parts;
    for (const auto& p : scene->primitives) parts.push_back(leaf(p.spec, p.id));
    const BooleanOp op = scene->op == geo::BooleanOp::Fuse     ? BooleanOp::Fuse
                         : scene->op == geo::BooleanOp::Common ? BooleanOp::Common
                                                               : BooleanOp::Cut;
    auto r = csg_combine(parts, op);
    ASSERT_TRUE(r.ok()) << r.error().message;
    EXPECT_NEAR(mass_properties(r->shape).volume, *scene->expected->volume,
                1e-7 * std::max(1.0, *scene->expected->volume));
    expect_sources_on_surfaces(r.value());
    auto back = read_native_model(write_native_model(r.value()));
    ASSERT_TRUE(back.ok()) << back.error().message;
    EXPECT_EQ(back->face_sources, r->face_sources);
    ++cases;
  }
  EXPECT_GE(cases, 33);
}

}  // namespace
}  // namespace csgtile::kernel
