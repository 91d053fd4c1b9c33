// Topology (paper §2) and access algorithms (§3.2): shapes, sharing, equality levels,
// locations, orientations, explorer, child map and ancestor index.

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <set>

#include "csgtile/kernel/explorer.h"
#include "csgtile/kernel/primitives.h"

namespace csgtile::kernel {
namespace {

Shape unwrap(Result<Shape> r) {
  EXPECT_TRUE(r.ok()) << (r.ok() ? "" : r.error().message);
  return r.ok() ? std::move(r).value() : Shape();
}

// The paper's Fig. 6 square: vertices 1..4 counter-clockwise, edge i from vertex i to i+1.
struct Square {
  std::vector<Shape> vertices, edges;
  Shape face;
};

Square make_square() {
  Square sq;
  const Vec3 corners[4] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  for (const Vec3& c : corners) sq.vertices.push_back(unwrap(ShapeFactory::vertex(c, 1e-7)));
  std::vector<Curve2dPtr> pcurves;
  for (int i = 0; i < 4; ++i) {
    const Vec3 a = corners[i], b = corners[(i + 1) % 4];
    sq.edges.push_back(
        unwrap(ShapeFactory::edge(std::make_shared<LineCurve>(a, b - a), 0.0, (b - a).norm(),
                                  sq.vertices[i], sq.vertices[(i + 1) % 4], 1e-7)));
    pcurves.push_back(
        std::make_shared<Line2d>(Vec2(a.x(), a.y()), Vec2(b.x() - a.x(), b.y() - a.y())));
  }
  Shape wire = unwrap(ShapeFactory::wire(sq.edges));
  sq.face =
      unwrap(ShapeFactory::face(std::make_shared<PlaneSurface>(Frame()), {wire}, {pcurves}, 1e-7));
  return sq;
}

TEST(Orientation, ComposeFollowsTable2) {
  EXPECT_EQ(compose(Orientation::Forward, Orientation::Reversed), Orientation::Reversed);
  EXPECT_EQ(compose(Orientation::Reversed, Orientation::Reversed), Orientation::Forward);
  EXPECT_EQ(compose(Orientation::Reversed, Orientation::Forward), Orientation::Reversed);
  EXPECT_EQ(compose(Orientation::Internal, Orientation::Forward), Orientation::Internal);
  EXPECT_EQ(compose(Orientation::External, Orientation::Reversed), Orientation::External);
  EXPECT_EQ(reversed(Orientation::Internal), Orientation::Internal);
}

TEST(Location, AcceptsSimilaritiesAndComposesLikeEquation5) {
  // Eq. (4) translation then eq. (5) rotation about X by π/2.
  Matrix34 t;
  t << 1, 0, 0, 2, 0, 1, 0, 3, 0, 0, 1, 4;
  Matrix34 r;
  r << 1, 0, 0, 0, 0, 0, -1, 0, 0, 1, 0, 0;
  auto lt = Location::from_matrix(t);
  auto lr = Location::from_matrix(r);
  ASSERT_TRUE(lt.ok() && lr.ok());
  const Location composed = lt.value() * lr.value();
  const Matrix34 expected = (Matrix34() << 1, 0, 0, 2, 0, 0, -1, 3, 0, 1, 0, 4).finished();
  EXPECT_TRUE(composed.matrix().isApprox(expected, 1e-15));
  const Vec3 p(1, 2, 3);
  EXPECT_TRUE(composed.apply_point(p).isApprox(lt->apply_point(lr->apply_point(p))));
  EXPECT_TRUE((composed * composed.inverse()).matrix().isApprox(Location().matrix(), 1e-14));
  // Uniform scale 2 with a rotation is a similarity.
  Matrix34 s = 2.0 * r;
  auto ls = Location::from_matrix(s);
  ASSERT_TRUE(ls.ok());
  EXPECT_DOUBLE_EQ(ls->scale(), 2.0);
}

// The identity is stored as nothing, so that the many child references at the identity cost
// a null pointer; composing with it is exact (the other side, bit for bit), and a stored
// transform has no negative zeros (equal transforms, equal bits, however they were made).
TEST(Location, IdentityIsExactAndCostsNothing) {
  EXPECT_TRUE(Location().is_identity());
  EXPECT_TRUE(Location::translation(Vec3(0.0, -0.0, 0.0)).is_identity());
  EXPECT_TRUE(Location().inverse().is_identity());
  auto from_identity = Location::from_matrix(Location().matrix());
  ASSERT_TRUE(from_identity.ok());
  EXPECT_TRUE(from_identity->is_identity());
  EXPECT_EQ(from_identity->hash(), 0u);

  const Location l = Location::rotation(Vec3(1, 2, 3), Vec3(0, 0, 1), 0.3) *
                     Location::translation(Vec3(-0.0, 5.0, -2.0));
  EXPECT_FALSE(l.is_identity());
  for (const Location& c : {l * Location(), Location() * l}) {
    EXPECT_EQ(c.matrix(), l.matrix());
    EXPECT_EQ(c.hash(), l.hash());
    EXPECT_TRUE(c == l);
  }
  const Location t = Location::translation(Vec3(-0.0, 1.0, 2.0));
  EXPECT_FALSE(std::signbit(t.translation().x()));
  EXPECT_FALSE(std::signbit(t.rotation()(0, 1)));
  // A reference to a body is a pointer, a location handle and an orientation: no matrix.
  EXPECT_LE(sizeof(Shape), 48u);
  EXPECT_LE(sizeof(Location), 16u);
}

TEST(Location, RejectsSingularShearedAndMirroringMatrices) {
  Matrix34 singular = Matrix34::Zero();
  singular(0, 0) = 1;
  auto a = Location::from_matrix(singular);
  ASSERT_FALSE(a.ok());
  EXPECT_EQ(a.error().code, ErrorCode::InvalidLocation);
  EXPECT_NE(a.error().message.find("singular"), std::string::npos);

  Matrix34 shear;
  shear << 1, 0.1, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0;
  auto b = Location::from_matrix(shear);
  ASSERT_FALSE(b.ok());
  EXPECT_NE(b.error().message.find("similarity"), std::string::npos);

  Matrix34 mirror;
  mirror << -1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0;
  auto c = Location::from_matrix(mirror);
  ASSERT_FALSE(c.ok());
  EXPECT_NE(c.error().message.find("mirror"), std::string::npos);

  Matrix34 nonuniform;
  nonuniform << 1, 0, 0, 0, 0, 2, 0, 0, 0, 0, 1, 0;
  EXPECT_FALSE(Location::from_matrix(nonuniform).ok());
}

TEST(Shape, ThreeEqualityLevels) {
  Shape box = unwrap(make_box(1, 2, 3));
  const Location moved = Location::translation(Vec3(1, 0, 0));
  EXPECT_TRUE(box.shares_body(box.moved(moved)));
  EXPECT_FALSE(box.is_same(box.moved(moved)));
  EXPECT_TRUE(box.is_same(box.reversed()));
  EXPECT_FALSE(box == box.reversed());
  EXPECT_TRUE(box == box.reversed().reversed());
  EXPECT_EQ(box.hash(), box.reversed().hash());
}

TEST(Shape, BoxSharesTwelveEdgesBetweenSixFacesWithOppositeOrientations) {
  Shape box = unwrap(make_box(1, 2, 3));
  const ShapeIndex edges = map_child_shapes(box, ShapeKind::Edge);
  const ShapeIndex vertices = map_child_shapes(box, ShapeKind::Vertex);
  EXPECT_EQ(map_child_shapes(box, ShapeKind::Face).size(), 6u);
  EXPECT_EQ(edges.size(), 12u);
  EXPECT_EQ(vertices.size(), 8u);
  std::vector<int> forward(12, 0), reversed_uses(12, 0);
  int uses = 0;
  for (const Shape& face : Explorer(box, ShapeKind::Face)) {
    for (const Shape& e : Explorer(face, ShapeKind::Edge)) {
      const std::size_t i = edges.find(e);
      ASSERT_NE(i, ShapeIndex::npos);
      (e.orientation() == Orientation::Forward ? forward : reversed_uses)[i]++;
      ++uses;
    }
  }
  EXPECT_EQ(uses, 24);
  for (int i = 0; i < 12; ++i) {
    EXPECT_EQ(forward[i], 1) << "edge " << i;
    EXPECT_EQ(reversed_uses[i], 1) << "edge " << i;
  }
}

TEST(Shape, ChildLocationIsTheCompositionOfItsParents) {
  Shape box = unwrap(make_box(1, 1, 1));
  const Location l1 = Location::translation(Vec3(10, 0, 0));
  const Location l2 = Location::rotation(Vec3::Zero(), Vec3::UnitZ(), std::numbers::pi / 2);
  Shape inner = unwrap(ShapeFactory::compound({box.moved(l2)}));
  Shape outer = inner.moved(l1);
  std::set<std::pair<long, long>> xy;
  for (const Shape& v : Explorer(outer, ShapeKind::Vertex)) {
    const Vec3 p = vertex_point(v);
    xy.insert({std::lround(p.x()), std::lround(p.y())});
    EXPECT_TRUE(v.location().matrix().isApprox((l1 * l2).matrix()));
  }
  // The unit box rotated by 90° about Z covers x in [-1, 0], then moves by 10 in x.
  EXPECT_EQ(xy, (std::set<std::pair<long, long>>{{9, 0}, {10, 0}, {9, 1}, {10, 1}}));
}

TEST(Shape, ReversingAParentReversesItsChildren) {
  Shape box = unwrap(make_box(1, 1, 1));
  std::vector<Orientation> a, b;
  for (const Shape& f : Explorer(box, ShapeKind::Face)) a.push_back(f.orientation());
  for (const Shape& f : Explorer(box.reversed(), ShapeKind::Face)) b.push_back(f.orientation());
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) EXPECT_EQ(b[i], reversed(a[i]));
}

TEST(Explorer, FindsAvoidsAndYieldsTheRoot) {
  Shape box = unwrap(make_box(1, 1, 1));
  int faces = 0, edges = 0, vertices_outside_faces = 0;
  for (const Shape& f : Explorer(box, ShapeKind::Face)) {
    EXPECT_EQ(f.kind(), ShapeKind::Face);
    ++faces;
  }
  for ([[maybe_unused]] const Shape& e : Explorer(box, ShapeKind::Edge)) ++edges;
  for ([[maybe_unused]] const Shape& v : Explorer(box, ShapeKind::Vertex, ShapeKind::Face)) {
    ++vertices_outside_faces;
  }
  EXPECT_EQ(faces, 6);
  EXPECT_EQ(edges, 24);
  EXPECT_EQ(vertices_outside_faces, 0);
  int roots = 0;
  for (const Shape& s : Explorer(box, ShapeKind::Solid)) roots += s.is_same(box);
  EXPECT_EQ(roots, 1);
  EXPECT_EQ(Explorer(Shape(), ShapeKind::Face).begin(), Explorer(Shape(), ShapeKind::Face).end());
}

TEST(AncestorIndex, ReproducesTable3OnTheSquare) {
  Square sq = make_square();
  AncestorIndex index(sq.face, ShapeKind::Vertex, ShapeKind::Edge);
  ASSERT_EQ(index.size(), 4u);
  for (int v = 0; v < 4; ++v) {
    const auto& ancestors = index.ancestors_of(sq.vertices[v]);
    ASSERT_EQ(ancestors.size(), 2u) << "vertex " << v + 1;
    // Table 3: the left edge ends at the vertex (vertex Reversed in it), the right edge
    // starts there. Vertex 1: left Edge4, right Edge1; vertex 2: Edge1, Edge2; ...
    Shape left, right;
    for (const Shape& e : ancestors) {
      for (const Shape& ev : Explorer(e, ShapeKind::Vertex)) {
        if (!ev.is_same(sq.vertices[v])) continue;
        (ev.orientation() == Orientation::Reversed ? left : right) = e;
      }
    }
    EXPECT_TRUE(left.is_same(sq.edges[(v + 3) % 4])) << "vertex " << v + 1;
    EXPECT_TRUE(right.is_same(sq.edges[v])) << "vertex " << v + 1;
  }
}

TEST(AncestorIndex, BoxEdgesHaveTwoFacesAndVerticesThreeEdges) {
  Shape box = unwrap(make_box(1, 2, 3).value().moved(Location::translation(Vec3(5, 5, 5))));
  AncestorIndex edge_faces(box, ShapeKind::Edge, ShapeKind::Face);
  AncestorIndex vertex_edges(box, ShapeKind::Vertex, ShapeKind::Edge);
  AncestorIndex face_solids(box, ShapeKind::Face, ShapeKind::Solid);
  ASSERT_EQ(edge_faces.size(), 12u);
  ASSERT_EQ(vertex_edges.size(), 8u);
  for (std::size_t i = 0; i < 12; ++i) EXPECT_EQ(edge_faces.ancestors(i).size(), 2u);
  for (std::size_t i = 0; i < 8; ++i) EXPECT_EQ(vertex_edges.ancestors(i).size(), 3u);
  for (std::size_t i = 0; i < face_solids.size(); ++i)
    EXPECT_EQ(face_solids.ancestors(i).size(), 1u);
  EXPECT_TRUE(edge_faces.ancestors_of(Shape()).empty());
}

TEST(AncestorIndex, SeamEdgeListsItsFaceOnce) {
  Shape cylinder = unwrap(make_cylinder(1, 2));
  AncestorIndex edge_faces(cylinder, ShapeKind::Edge, ShapeKind::Face);
  int seams = 0;
  for (std::size_t i = 0; i < edge_faces.size(); ++i) {
    if (edge_faces.ancestors(i).size() == 1) ++seams;  // the seam: used twice by one face
  }
  EXPECT_EQ(seams, 1);
}

TEST(ChildMap, SameSolidAtTwoLocationsCountsTwice) {
  Shape box = unwrap(make_box(1, 1, 1));
  Shape pair =
      unwrap(ShapeFactory::compound({box, box.moved(Location::translation(Vec3(3, 0, 0)))}));
  EXPECT_EQ(map_child_shapes(pair, ShapeKind::Solid).size(), 2u);
  EXPECT_EQ(map_child_shapes(pair, ShapeKind::Edge).size(), 24u);
  Shape twice = unwrap(ShapeFactory::compound({box, box.reversed()}));
  EXPECT_EQ(map_child_shapes(twice, ShapeKind::Edge).size(), 12u);
  const auto counts = count_shapes(pair);
  EXPECT_EQ(counts[static_cast<int>(ShapeKind::Vertex)], 16u);
  EXPECT_EQ(counts[static_cast<int>(ShapeKind::Compound)], 1u);
}

TEST(ShapeFactory, EnforcesKindsAndToleranceOrder) {
  Shape v = unwrap(ShapeFactory::vertex(Vec3::Zero(), 1e-7));
  Shape w = unwrap(ShapeFactory::vertex(Vec3(1, 0, 0), 1e-7));
  auto too_loose = ShapeFactory::edge(std::make_shared<LineCurve>(Vec3::Zero(), Vec3::UnitX()), 0,
                                      1, v, w, 1e-3);
  ASSERT_FALSE(too_loose.ok());
  EXPECT_NE(too_loose.error().message.find("exceeds"), std::string::npos);
  auto far = ShapeFactory::edge(std::make_shared<LineCurve>(Vec3::Zero(), Vec3::UnitX()), 0, 2, v,
                                w, 1e-7);
  EXPECT_FALSE(far.ok());
  EXPECT_FALSE(ShapeFactory::shell({v}).ok());
  EXPECT_FALSE(ShapeFactory::vertex(Vec3(NAN, 0, 0), 1e-7).ok());
  EXPECT_FALSE(ShapeFactory::vertex(Vec3::Zero(), -1).ok());
}

}  // namespace
}  // namespace csgtile::kernel
