// The topology index (GeoPackage): readable by GDAL and valid for its validator, ancestor and
// child tables equal to the kernel's maps, exact relations, stable ids and bytes, the README's
// SQL recipes, `csgtile query`, and the index of a run.

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <numbers>

#include "csgtile/geo/crs.h"
#include "csgtile/kernel/explorer.h"
#include "csgtile/kernel/mass_properties.h"
#include "csgtile/worker/publish.h"
#include "csgtile/worker/run.h"
#include "export/index_rows.h"
#include "export/topology_index.h"
#include "index_object_builder.h"
#include "model_builders.h"
#include "test_commands.h"
#include "test_support.h"

namespace csgtile::worker {
namespace {

namespace fs = std::filesystem;
using kernel::ShapeKind;
using kernel::Vec3;

// ---- the README's recipes, verbatim ---------------------------------------------------------

constexpr const char* kEdgesAtVertex =
    "SELECT e.key FROM shapes v "
    "JOIN shape_ancestors a ON a.shape_id = v.id AND a.ancestor_kind = 'edge' "
    "JOIN shapes e ON e.id = a.ancestor_id "
    "WHERE v.key = ?1 ORDER BY a.position";
constexpr const char* kFacesOfSolid =
    "SELECT f.key FROM shapes s "
    "JOIN shape_ancestors a ON a.ancestor_id = s.id AND a.ancestor_kind = 'solid' "
    "JOIN shapes f ON f.id = a.shape_id "
    "WHERE s.key = ?1 ORDER BY f.id";
constexpr const char* kObjectsTouching =
    "SELECT other_id, shared_area FROM object_relations "
    "WHERE object_id = ?1 AND relation = 'touches' ORDER BY other_id";

// ---- objects ---------------------------------------------------------------------------------

kernel::PrimitiveSpec box(const Vec3& at, const Vec3& size) { return test::box_at(at, size); }
kernel::PrimitiveSpec cylinder(const Vec3& at, double r, double h) {
  return test::cylinder_at(at, r, h);
}
using test::leaf;

kernel::CsgModel combine(const kernel::CsgModel& a, const kernel::CsgModel& b,
                         kernel::BooleanOp op) {
  auto m = kernel::csg_boolean(a, b, op);
  EXPECT_TRUE(m.ok()) << m.error().message;
  return std::move(m).value();
}

IndexObject object(const std::string& id, kernel::CsgModel model) {
  return test::index_object(id, std::move(model));
}

// Two fused boxes, a drilled block, a cylinder standing on a box, a small box in a big one.
const std::vector<IndexObject>& sample_objects() {
  static const std::vector<IndexObject> objects = [] {
    std::vector<IndexObject> out;
    out.push_back(
        object("fused", combine(leaf(box({0, 0, 0}, {2, 1, 1}), "a"),
                                leaf(box({1, 0, 0.5}, {2, 1, 1}), "b"), kernel::BooleanOp::Fuse)));
    out[0].primitives[0].inliers = 100;
    out[0].primitives[0].rms = 0.01;
    out[0].primitives[0].coverage = 0.9;
    out[0].primitives[1].inliers = 300;
    out[0].primitives[1].rms = 0.02;
    out[0].primitives[1].coverage = 0.5;
    out[0].primitives[0].within_2sigma = 0.9;  // the other has none: the share is its own
    out.push_back(object(
        "drilled", combine(leaf(box({5, 0, 0}, {3, 2, 2}), "block"),
                           leaf(cylinder({6.5, 1, -1}, 0.5, 4), "hole"), kernel::BooleanOp::Cut)));
    out.push_back(object("base", leaf(box({10, 0, 0}, {2, 2, 1}), "base")));
    out.push_back(object("post", leaf(cylinder({11, 1, 1}, 0.5, 1), "post")));
    out.push_back(object("big", leaf(box({20, 0, 0}, {4, 4, 4}), "big")));
    out.push_back(object("small", leaf(box({21, 1, 1}, {1, 1, 1}), "small")));
    return out;
  }();
  return objects;
}

// ---- helpers ---------------------------------------------------------------------------------

using test::CommandResult;
using test::quoted;
CommandResult run_command(const std::string& command) { return test::run_command(command, false); }

constexpr const char* kValidator =
    "/usr/lib/python3/dist-packages/osgeo_utils/samples/validate_gpkg.py";

// GDAL's tools come from deploy/setup.sh; without them the GDAL checks skip, unless
// CSGTILE_REQUIRE_GDAL=1 makes their absence a failure (CI).
bool gdal_available(std::string& why) {
  const bool ogrinfo = run_command("ogrinfo --version").exit_code == 0;
  const bool validator = fs::exists(kValidator) && fs::exists("/usr/bin/python3");
  if (ogrinfo && validator) return true;
  why = std::string(ogrinfo ? "" : "ogrinfo (gdal-bin) ") +
        (validator ? "" : "validate_gpkg.py (python3-gdal) ") +
        "not installed; run deploy/setup.sh";
  return false;
}

#define REQUIRE_GDAL()                                                         \
  do {                                                                         \
    std::string why_;                                                          \
    if (!gdal_available(why_)) {                                               \
      const char* require_ = std::getenv("CSGTILE_REQUIRE_GDAL");              \
      if (require_ != nullptr && std::string(require_) == "1") FAIL() << why_; \
      GTEST_SKIP() << why_;                                                    \
    }                                                                          \
  } while (false)

// The key the index gives a sub-shape of an object: "<object>/<kind>/<index>".
std::string key_of(const std::string& object_id, const kernel::Shape& root,
                   const kernel::Shape& s) {
  const std::size_t i = kernel::map_child_shapes(root, s.kind()).find(s);
  EXPECT_NE(i, kernel::ShapeIndex::npos);
  return object_id + "/" + kernel::shape_kind_name(s.kind()) + "/" + std::to_string(i);
}

class TopologyIndexTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new test::TempDir("csgtile-topology-index-");
    IndexOptions options;
    const auto crs = geo::crs_from_epsg(28992);
    ASSERT_TRUE(crs.ok());
    options.srs = {28992, "EPSG", 28992, crs->name, geo::crs_to_wkt1(crs.value())};
    options.to_srs = [](const Vec3& p) { return Vec3(p + Vec3(155000, 463000, 0)); };
    const Failure st = write_topology_index(index_path(), sample_objects(), options, &stats_);
    ASSERT_TRUE(st.ok()) << st.message;
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }
  static fs::path index_path() { return *dir_ / "index.gpkg"; }
  std::unique_ptr<TopologyIndexReader> reader() const {
    auto r = TopologyIndexReader::open(index_path());
    EXPECT_TRUE(r.ok()) << r.error().message;
    return std::move(r).value();
  }
  static test::TempDir* dir_;
  static IndexStats stats_;
};
test::TempDir* TopologyIndexTest::dir_ = nullptr;
IndexStats TopologyIndexTest::stats_;

// ---- GDAL ------------------------------------------------------------------------------------

TEST_F(TopologyIndexTest, OgrinfoReadsTheObjectsLayerWithCountTypeAndCrs) {
  REQUIRE_GDAL();
  const CommandResult r = run_command("ogrinfo -ro -so " + quoted(index_path()) + " objects");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_NE(r.out.find("Feature Count: 6"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("Geometry: 3D Multi Polygon"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("Amersfoort / RD New"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("ID[\"EPSG\",28992]"), std::string::npos) << r.out;
  // The topology tables are listed as (non-spatial) layers.
  const CommandResult all = run_command("ogrinfo -ro " + quoted(index_path()));
  for (const char* table : {"shapes", "shape_children", "shape_ancestors", "object_relations",
                            "csg_nodes", "face_sources", "primitives"}) {
    EXPECT_NE(all.out.find(std::string(": ") + table + " (None)"), std::string::npos) << table;
  }
}

TEST_F(TopologyIndexTest, GdalGeoPackageValidatorPasses) {
  REQUIRE_GDAL();
  const CommandResult r = run_command(std::string("/usr/bin/python3 ") + kValidator +
                                      " --extra -k " + quoted(index_path()));
  EXPECT_EQ(r.exit_code, 0) << r.out;
}

TEST_F(TopologyIndexTest, UndefinedCartesianIndexIsValidToo) {
  REQUIRE_GDAL();
  const fs::path path = *dir_ / "local.gpkg";
  ASSERT_TRUE(write_topology_index(path, {sample_objects()[0]}).ok());
  const CommandResult info = run_command("ogrinfo -ro -so " + quoted(path) + " objects");
  EXPECT_NE(info.out.find("Feature Count: 1"), std::string::npos) << info.out;
  EXPECT_NE(info.out.find("Undefined Cartesian SRS"), std::string::npos) << info.out;
  EXPECT_EQ(
      run_command(std::string("/usr/bin/python3 ") + kValidator + " " + quoted(path)).exit_code, 0);
}

// ---- kernel maps -----------------------------------------------------------------------------

TEST_F(TopologyIndexTest, AncestorTablesEqualTheKernelAncestorIndex) {
  const auto index = reader();
  // The materialised pairs and three that the reader answers by walking references upwards.
  const std::pair<ShapeKind, ShapeKind> pairs[] = {
      {ShapeKind::Vertex, ShapeKind::Edge}, {ShapeKind::Edge, ShapeKind::Face},
      {ShapeKind::Face, ShapeKind::Shell},  {ShapeKind::Face, ShapeKind::Solid},
      {ShapeKind::Vertex, ShapeKind::Face}, {ShapeKind::Edge, ShapeKind::Wire},
      {ShapeKind::Vertex, ShapeKind::Solid}};
  std::size_t checked = 0;
  for (const IndexObject& o : sample_objects()) {
    const kernel::Shape& root = o.model.shape;
    for (const auto& [child, ancestor] : pairs) {
      const kernel::AncestorIndex kernel_map(root, child, ancestor);
      ASSERT_EQ(kernel_map.size(), kernel::map_child_shapes(root, child).size());
      for (std::size_t i = 0; i < kernel_map.size(); ++i) {
        const auto shape = index->shape(key_of(o.id, root, kernel_map.keys()[i]));
        ASSERT_TRUE(shape.ok()) << shape.error().message;
        const auto rows = index->ancestors(shape->id, kernel::shape_kind_name(ancestor));
        ASSERT_TRUE(rows.ok()) << rows.error().message;
        std::vector<std::string> expected, got;
        for (const kernel::Shape& a : kernel_map.ancestors(i))
          expected.push_back(key_of(o.id, root, a));
        for (const ShapeRow& a : rows.value()) got.push_back(a.key);
        EXPECT_EQ(got, expected) << shape->key << " -> " << kernel::shape_kind_name(ancestor);
        ++checked;
      }
    }
  }
  EXPECT_GT(checked, 300u);
}

TEST_F(TopologyIndexTest, SubShapeReferencesReproduceEveryBody) {
  const auto index = reader();
  for (const IndexObject& o : sample_objects()) {
    const kernel::Shape& root = o.model.shape;
    for (int k = 0; k < kernel::kShapeKindCount; ++k) {
      const kernel::ShapeIndex map = kernel::map_child_shapes(root, static_cast<ShapeKind>(k));
      for (const kernel::Shape& s : map.shapes()) {
        const auto shape = index->shape(key_of(o.id, root, s));
        ASSERT_TRUE(shape.ok());
        const auto rows = index->children(shape->id);
        ASSERT_TRUE(rows.ok());
        const auto& refs = s.body().children();
        ASSERT_EQ(rows->size(), refs.size()) << shape->key;
        for (std::size_t c = 0; c < refs.size(); ++c) {
          const ChildRow& row = rows.value()[c];
          EXPECT_EQ(row.position, static_cast<std::int64_t>(c));
          EXPECT_EQ(row.child.key, key_of(o.id, root, s.child(c)));
          EXPECT_EQ(row.orientation, kernel::orientation_name(refs[c].orientation()));
          EXPECT_EQ(row.location.empty(), refs[c].location().is_identity());
        }
      }
    }
  }
}

TEST_F(TopologyIndexTest, ShapeIdsFollowObjectKindAndMapOrder) {
  const auto index = reader();
  std::int64_t expected = 1;
  for (const IndexObject& o : sample_objects()) {
    for (int k = 0; k < kernel::kShapeKindCount; ++k) {
      const auto kind = static_cast<ShapeKind>(k);
      const std::size_t n = kernel::map_child_shapes(o.model.shape, kind).size();
      for (std::size_t i = 0; i < n; ++i, ++expected) {
        const auto s = index->shape(std::to_string(expected));
        ASSERT_TRUE(s.ok());
        EXPECT_EQ(s->key, o.id + "/" + kernel::shape_kind_name(kind) + "/" + std::to_string(i));
      }
    }
  }
  EXPECT_EQ(static_cast<std::size_t>(expected - 1), stats_.shapes);
  const auto unknown = index->shape("no-such/edge/0");
  ASSERT_FALSE(unknown.ok());
  EXPECT_EQ(unknown.error().code, ErrorCode::InputInvalid);
  EXPECT_NE(unknown.error().message.find("no-such/edge/0"), std::string::npos);
}

// ---- relations -------------------------------------------------------------------------------

TEST_F(TopologyIndexTest, RelationsTouchContainAndSkipDisjointPairs) {
  const auto index = reader();
  const auto post = index->relations("post");
  ASSERT_TRUE(post.ok());
  ASSERT_EQ(post->size(), 1u);
  EXPECT_EQ(post.value()[0].other_id, "base");
  EXPECT_EQ(post.value()[0].relation, "touches");
  ASSERT_TRUE(post.value()[0].shared_area.has_value());
  EXPECT_NEAR(*post.value()[0].shared_area, std::numbers::pi * 0.25, 1e-9 * std::numbers::pi);

  const auto big = index->relations("big");
  ASSERT_TRUE(big.ok());
  ASSERT_EQ(big->size(), 1u);
  EXPECT_EQ(big.value()[0].other_id, "small");
  EXPECT_EQ(big.value()[0].relation, "contains");
  EXPECT_NEAR(big.value()[0].common_volume.value_or(0), 1.0, 1e-12);
  const auto small = index->relations("small");
  ASSERT_TRUE(small.ok());
  ASSERT_EQ(small->size(), 1u);
  EXPECT_EQ(small.value()[0].relation, "within");

  for (const char* alone : {"fused", "drilled"}) {
    const auto none = index->relations(alone);
    ASSERT_TRUE(none.ok());
    EXPECT_TRUE(none->empty()) << alone;
  }
  const auto missing = index->relations("nobody");
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(missing.error().message.find("nobody"), std::string::npos);
  EXPECT_EQ(stats_.relations, 2u);
}

// The same pairs with the same kinds and measures, bit for bit.
void expect_same_relations(const std::vector<ObjectRelation>& a,
                           const std::vector<ObjectRelation>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].a, b[i].a);
    EXPECT_EQ(a[i].b, b[i].b);
    EXPECT_EQ(a[i].kind, b[i].kind);
    EXPECT_EQ(a[i].shared_area, b[i].shared_area);
    EXPECT_EQ(a[i].common_volume, b[i].common_volume);
  }
}

TEST(Relations, OverlapAndEqualityAreExact) {
  const auto a = leaf(box({0, 0, 0}, {2, 2, 2}), "a").shape;
  const auto b = leaf(box({1, 1, 1}, {2, 2, 2}), "b").shape;
  const auto c = leaf(box({0, 0, 0}, {2, 2, 2}), "c").shape;
  const auto rows = compute_relations({a, b, c}, 1e-7);
  ASSERT_EQ(rows.size(), 3u);
  EXPECT_EQ(rows[0].kind, RelationKind::Overlaps);
  EXPECT_NEAR(rows[0].common_volume, 1.0, 1e-12);
  EXPECT_EQ(rows[1].kind, RelationKind::Equals);  // a, c
  EXPECT_EQ(rows[1].b, 2u);
  EXPECT_EQ(rows[2].kind, RelationKind::Overlaps);  // b, c
}

// An object made of overlapping solids (a plain set) is compared as their union: two
// overlapping 2-cubes (union 12, sum 16) inside a larger box are within it, not overlapping.
TEST(Relations, ObjectOfOverlappingSolidsIsTheirUnion) {
  const auto left = leaf(box({0, 0, 0}, {2, 2, 2}), "left").shape;
  const auto right = leaf(box({1, 0, 0}, {2, 2, 2}), "right").shape;
  const auto pair = kernel::ShapeFactory::compound({left, right}).value();
  const auto outer = leaf(box({-1, -1, -1}, {5, 4, 4}), "outer").shape;
  const auto rows = compute_relations({pair, outer}, 1e-7);
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_EQ(rows[0].kind, RelationKind::Within);
  EXPECT_NEAR(rows[0].common_volume, 12.0, 1e-9);
}

TEST(Relations, ThreadCountDoesNotChangeTheResult) {
  std::vector<kernel::Shape> solids;
  for (const IndexObject& o : sample_objects()) solids.push_back(o.model.shape);
  expect_same_relations(compute_relations(solids, 1e-7, 1), compute_relations(solids, 1e-7, 4));
}

// Skipped pairs (a run's index skips the pairs inside a cell, classified by the cell) leave
// the other pairs exactly as the classification of every pair gives them, and objects that
// take part in no unskipped pair are not measured: here a row of houses across two cells,
// one of them a set of two overlapping solids, and a shed far from the border.
TEST(Relations, SkippedPairsLeaveTheOthersAsTheFullClassification) {
  std::vector<kernel::Shape> solids;
  std::vector<int> cell;
  for (int i = 0; i < 6; ++i) {  // party walls at x = 2, 4, ...; the cell border at x = 6
    solids.push_back(leaf(box({2.0 * i, 0, 0}, {2, 3, 4 + 0.5 * i}), "house").shape);
    cell.push_back(i < 3 ? 0 : 1);
  }
  const auto left = leaf(box({12, 0, 0}, {2, 3, 4}), "l").shape;
  const auto right = leaf(box({13, 0, 0}, {2, 3, 5}), "r").shape;
  solids.push_back(kernel::ShapeFactory::compound({left, right}).value());  // touches house 5
  cell.push_back(1);
  solids.push_back(leaf(box({5, 1, 0}, {2, 1, 2}), "overlapping").shape);  // across the border
  cell.push_back(1);
  solids.push_back(leaf(box({40, 40, 0}, {2, 2, 2}), "shed").shape);
  cell.push_back(1);

  const auto all = compute_relations(solids, 1e-7, 1);
  const auto across = compute_relations(
      solids, 1e-7, 1, [&cell](std::size_t i, std::size_t j) { return cell[i] == cell[j]; });
  std::vector<ObjectRelation> expected;
  for (const ObjectRelation& r : all) {
    if (cell[r.a] != cell[r.b]) expected.push_back(r);
  }
  EXPECT_EQ(across.size(), 2u);  // the wall at x = 6, the overlapping box with house 2
  expect_same_relations(across, expected);
  // The full classification: six party walls (houses 0..5 and the set), each the depth
  // times the lower of the two heights (the set's wall: its left solid's, 4).
  int walls = 0;
  for (const ObjectRelation& r : all) {
    if (r.kind != RelationKind::Touches || r.b > 6 || r.b != r.a + 1) continue;
    ++walls;
    const double height = r.a == 5 ? 4.0 : 4.0 + 0.5 * static_cast<double>(r.a);
    EXPECT_NEAR(r.shared_area, 3.0 * height, 1e-9) << r.a;
  }
  EXPECT_EQ(walls, 6);
  const auto none =
      compute_relations(solids, 1e-7, 1, [](std::size_t, std::size_t) { return true; });
  EXPECT_TRUE(none.empty());
}

// A pair whose Boolean fails (here: one operand is a face, not a solid; in runs, surface pairs
// the kernel cannot intersect yet or results its checker refuses) is reported as "unknown"
// with the kernel's error, not dropped, and nothing crashes.
TEST(Relations, FailingBooleanGivesUnknownWithTheReason) {
  const auto solid = leaf(box({0, 0, 0}, {2, 2, 2}), "solid").shape;
  const auto face =
      kernel::map_child_shapes(leaf(box({1, 1, 1}, {2, 2, 2}), "b").shape, ShapeKind::Face)[0];
  const auto rows = compute_relations({solid, face}, 1e-7);
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_EQ(rows[0].kind, RelationKind::Unknown);
  EXPECT_EQ(rows[0].reason.rfind("fuse: invalid_argument: ", 0), 0u) << rows[0].reason;
}

// ---- recipes, objects layer --------------------------------------------------------------------

TEST_F(TopologyIndexTest, ReadmeRecipesAnswerLikeTheKernel) {
  const auto index = reader();
  for (const IndexObject& o : sample_objects()) {
    const kernel::Shape& root = o.model.shape;
    const kernel::AncestorIndex edges(root, ShapeKind::Vertex, ShapeKind::Edge);
    for (std::size_t i = 0; i < edges.size(); ++i) {
      const auto rows = index->sql(kEdgesAtVertex, {key_of(o.id, root, edges.keys()[i])});
      ASSERT_TRUE(rows.ok()) << rows.error().message;
      ASSERT_EQ(rows->size(), edges.ancestors(i).size());
      for (std::size_t e = 0; e < rows->size(); ++e) {
        EXPECT_EQ(rows.value()[e][0], key_of(o.id, root, edges.ancestors(i)[e]));
      }
    }
    const kernel::ShapeIndex solids = kernel::map_child_shapes(root, ShapeKind::Solid);
    for (const kernel::Shape& solid : solids.shapes()) {
      const auto rows = index->sql(kFacesOfSolid, {key_of(o.id, root, solid)});
      ASSERT_TRUE(rows.ok());
      const kernel::ShapeIndex faces = kernel::map_child_shapes(solid, ShapeKind::Face);
      ASSERT_EQ(rows->size(), faces.size());
      for (std::size_t f = 0; f < faces.size(); ++f) {
        EXPECT_EQ(rows.value()[f][0], key_of(o.id, root, faces[f]));
      }
    }
  }
  // The README shows the same statements.
  const std::string readme = test::read_file(test::source_dir() / "README.md");
  for (const char* recipe : {kEdgesAtVertex, kFacesOfSolid, kObjectsTouching}) {
    EXPECT_NE(readme.find(std::string(recipe) + ";"), std::string::npos) << recipe;
  }
  const auto touching = index->sql(kObjectsTouching, {"base"});
  ASSERT_TRUE(touching.ok());
  ASSERT_EQ(touching->size(), 1u);
  EXPECT_EQ(touching.value()[0][0], "post");
  EXPECT_NEAR(std::stod(touching.value()[0][1]), std::numbers::pi * 0.25, 1e-9);
  // Each recipe is answered through indexes, never by scanning a table.
  for (const char* recipe : {kEdgesAtVertex, kFacesOfSolid, kObjectsTouching}) {
    const auto plan = index->sql(std::string("EXPLAIN QUERY PLAN ") + recipe, {"x"});
    ASSERT_TRUE(plan.ok());
    for (const auto& row : plan.value()) {
      EXPECT_NE(row.back().rfind("SCAN", 0), 0u) << recipe << ": " << row.back();
    }
  }
}

TEST_F(TopologyIndexTest, ObjectsLayerAttributes) {
  const auto index = reader();
  const auto rows = index->sql(
      "SELECT object_id, cell, primitive_count, primitive_types, volume, valid, fit_rms, "
      "fit_coverage, min_x, max_z, fit_within_2sigma FROM objects ORDER BY fid");
  ASSERT_TRUE(rows.ok());
  ASSERT_EQ(rows->size(), 6u);
  const auto& fused = rows.value()[0];
  EXPECT_EQ(fused[0], "fused");
  EXPECT_EQ(fused[1], "0");
  EXPECT_EQ(fused[2], "2");
  EXPECT_EQ(fused[3], "box");
  EXPECT_NEAR(std::stod(fused[4]), 2 + 2 - 0.5, 1e-12);
  EXPECT_EQ(fused[5], "1");
  EXPECT_NEAR(std::stod(fused[6]), std::sqrt((100 * 1e-4 + 300 * 4e-4) / 400), 1e-15);
  EXPECT_NEAR(std::stod(fused[7]), (100 * 0.9 + 300 * 0.5) / 400, 1e-15);
  EXPECT_DOUBLE_EQ(std::stod(fused[8]), 155000.0);
  EXPECT_DOUBLE_EQ(std::stod(fused[9]), 1.5);
  EXPECT_DOUBLE_EQ(std::stod(fused[10]), 0.9);
  EXPECT_EQ(rows.value()[2][10], "NULL");  // not fitted
  EXPECT_EQ(rows.value()[1][3], "box,cylinder");
  EXPECT_EQ(rows.value()[2][6], "NULL");  // not fitted
  // CSG nodes, face sources and primitives of the drilled block.
  const auto nodes = index->sql(
      "SELECT node, kind, label, parent, children, primitive_type FROM "
      "csg_nodes WHERE object_id = 'drilled' ORDER BY node");
  ASSERT_TRUE(nodes.ok());
  ASSERT_EQ(nodes->size(), 3u);
  EXPECT_EQ(nodes.value()[0],
            (std::vector<std::string>{"0", "primitive", "block", "2", "[]", "box"}));
  EXPECT_EQ(nodes.value()[2],
            (std::vector<std::string>{"2", "cut", "NULL", "NULL", "[0,1]", "NULL"}));
  const auto hole_faces =
      index->sql("SELECT count(*) FROM face_sources WHERE object_id = 'drilled' AND node = 1");
  ASSERT_TRUE(hole_faces.ok());
  EXPECT_EQ(hole_faces.value()[0][0], "1");  // the bore: the cylinder's lateral face
}

// Signed volume enclosed by the boundary polygons (divergence theorem over each ring's fan):
// the rings are closed and outward when it equals the solid's volume.
double polygons_volume(const std::vector<detail::Polygon3>& polygons) {
  double v = 0.0;
  for (const auto& p : polygons) {
    for (const auto& ring : p.rings) {
      for (std::size_t i = 1; i + 2 < ring.size(); ++i) {
        v += ring[0].dot(ring[i].cross(ring[i + 1])) / 6.0;
      }
    }
  }
  return v;
}

// The exporters take the validity the job checked once (IndexObject::valid) rather than
// checking the model again; without it they check it.
TEST(TopologyIndexRows, ValidityCheckedOnceIsTheOneWritten) {
  std::vector<IndexObject> objects = sample_objects();
  ASSERT_GE(objects.size(), 2u);
  for (const IndexObject& o : objects) EXPECT_TRUE(model_valid(o)) << o.id;
  objects[1].valid = false;  // as if the job's checker had refused it
  IndexStats stats;
  const auto rows = detail::build_index_rows(objects, {}, stats);
  ASSERT_TRUE(rows.ok());
  EXPECT_TRUE(rows->objects[0].valid);
  EXPECT_FALSE(rows->objects[1].valid);
}

TEST(TopologyIndexRows, BoundaryPolygonsAreClosedAndOutward) {
  IndexStats stats;
  const auto rows = detail::build_index_rows(sample_objects(), {}, stats);
  ASSERT_TRUE(rows.ok());
  for (std::size_t i = 0; i < sample_objects().size(); ++i) {
    const detail::ObjectRecord& o = rows->objects[i];
    ASSERT_TRUE(o.has_geometry) << o.object_id;
    const double exact = kernel::mass_properties(sample_objects()[i].model.shape).volume;
    // Planar faces are exact; curved ones are inscribed meshes within the chordal tolerance.
    const bool curved = o.primitive_types.find("cylinder") != std::string::npos;
    EXPECT_NEAR(polygons_volume(o.boundary), exact, (curved ? 0.05 : 1e-12) * exact) << o.object_id;
    // Watertight: every ring segment is met once in the opposite direction.
    std::map<std::array<double, 6>, int> segments;
    for (const auto& p : o.boundary) {
      for (const auto& ring : p.rings) {
        ASSERT_GE(ring.size(), 4u);
        EXPECT_EQ(ring.front(), ring.back());
        for (std::size_t k = 0; k + 1 < ring.size(); ++k) {
          const Vec3& a = ring[k];
          const Vec3& b = ring[k + 1];
          ++segments[{a.x(), a.y(), a.z(), b.x(), b.y(), b.z()}];
        }
      }
    }
    for (const auto& [s, n] : segments) {
      EXPECT_EQ(n, 1) << o.object_id;
      const auto back = segments.find({s[3], s[4], s[5], s[0], s[1], s[2]});
      EXPECT_TRUE(back != segments.end() && back->second == 1) << o.object_id;
    }
  }
  EXPECT_TRUE(stats.warnings.empty());
}

// ---- stability, errors -----------------------------------------------------------------------

TEST_F(TopologyIndexTest, SameInputGivesTheSameIdsAndBytes) {
  const fs::path a = *dir_ / "a.gpkg", b = *dir_ / "b.gpkg";
  ASSERT_TRUE(write_topology_index(a, sample_objects()).ok());
  ASSERT_TRUE(write_topology_index(b, sample_objects()).ok());
  const std::string bytes = test::read_file(a);
  EXPECT_GT(bytes.size(), 4096u);
  EXPECT_EQ(bytes, test::read_file(b));
  // No temporary is left beside the outputs.
  for (const auto& entry : fs::directory_iterator(dir_->path())) {
    EXPECT_EQ(entry.path().filename().string().find(".tmp."), std::string::npos) << entry.path();
  }
}

TEST(TopologyIndexErrors, BadObjectsAndUnwritablePathsAreNamedErrors) {
  test::TempDir dir("csgtile-topology-index-errors-");
  std::vector<IndexObject> twice = {sample_objects()[2], sample_objects()[2]};
  const Failure duplicate = write_topology_index(dir / "x.gpkg", twice);
  ASSERT_FALSE(duplicate.ok());
  EXPECT_EQ(duplicate.code, ErrorCode::InputInvalid);
  EXPECT_NE(duplicate.message.find("\"base\""), std::string::npos);
  EXPECT_FALSE(fs::exists(dir / "x.gpkg"));

  const Failure unwritable = write_topology_index("/proc/csgtile/x.gpkg", {sample_objects()[2]});
  ASSERT_FALSE(unwritable.ok());
  EXPECT_EQ(unwritable.code, ErrorCode::Io);

  std::ofstream(dir / "not.gpkg") << "plain text, not SQLite";
  const auto not_index = TopologyIndexReader::open(dir / "not.gpkg");
  ASSERT_FALSE(not_index.ok());
  EXPECT_EQ(not_index.error().code, ErrorCode::InputInvalid);
  EXPECT_EQ(TopologyIndexReader::open(dir / "missing.gpkg").error().code, ErrorCode::Io);
}

// ---- csgtile query ---------------------------------------------------------------------------

TEST_F(TopologyIndexTest, QueryCommandAnswersMatchTheKernelMaps) {
  const std::string bin = test::csgtile_binary().string() + " query " + quoted(index_path()) + " ";
  const IndexObject& drilled = sample_objects()[1];
  const kernel::Shape& root = drilled.model.shape;

  // --children of every face: the face body's wires.
  const kernel::ShapeIndex faces = kernel::map_child_shapes(root, ShapeKind::Face);
  for (const kernel::Shape& face : faces.shapes()) {
    const CommandResult r =
        run_command(bin + "--children " + key_of("drilled", root, face) + " --json");
    ASSERT_EQ(r.exit_code, 0) << r.out;
    const auto j = nlohmann::json::parse(r.out);
    ASSERT_EQ(j["children"].size(), face.child_count());
    for (std::size_t c = 0; c < face.child_count(); ++c) {
      EXPECT_EQ(j["children"][c]["key"], key_of("drilled", root, face.child(c)));
    }
  }
  // --ancestors of every vertex: its edges, as AncestorIndex lists them (by numeric id too).
  const kernel::AncestorIndex edges(root, ShapeKind::Vertex, ShapeKind::Edge);
  for (std::size_t i = 0; i < edges.size(); ++i) {
    const CommandResult r = run_command(
        bin + "--ancestors " + key_of("drilled", root, edges.keys()[i]) + " --kind edge --json");
    ASSERT_EQ(r.exit_code, 0) << r.out;
    const auto j = nlohmann::json::parse(r.out);
    ASSERT_EQ(j["ancestors"].size(), edges.ancestors(i).size());
    for (std::size_t e = 0; e < edges.ancestors(i).size(); ++e) {
      EXPECT_EQ(j["ancestors"][e]["key"], key_of("drilled", root, edges.ancestors(i)[e]));
    }
    const std::string by_id =
        run_command(bin + "--ancestors " + std::to_string(j["shape"]["id"].get<long long>()) +
                    " --kind edge --json")
            .out;
    EXPECT_EQ(nlohmann::json::parse(by_id)["ancestors"], j["ancestors"]);
  }
  // --relations, and the text form.
  const CommandResult rel = run_command(bin + "--relations post --json");
  ASSERT_EQ(rel.exit_code, 0);
  const auto j = nlohmann::json::parse(rel.out);
  ASSERT_EQ(j["relations"].size(), 1u);
  EXPECT_EQ(j["relations"][0]["other"], "base");
  EXPECT_EQ(j["relations"][0]["relation"], "touches");
  EXPECT_EQ(run_command(bin + "--relations small").out.rfind("big\twithin\t", 0), 0u);

  // Unknown id: input_invalid (65) naming it; a file that is not there: io (74).
  const CommandResult unknown = run_command(bin + "--children drilled/edge/999 --json");
  EXPECT_EQ(unknown.exit_code, 65);
  EXPECT_NE(unknown.out.find("drilled/edge/999"), std::string::npos) << unknown.out;
  EXPECT_EQ(
      run_command(test::csgtile_binary().string() + " query /nonexistent/index.gpkg --relations x")
          .exit_code,
      74);
  EXPECT_EQ(run_command(bin + "--ancestors 1").exit_code, 64);  // --kind missing
}

// ---- the run's index ---------------------------------------------------------------------------

TEST(RunIndex, RunPublishesTheIndexInItsManifest) {
  test::TempDir dir("csgtile-run-index-");
  config::Config c;
  c.run.name = "t";
  c.run.output = (dir / "out").string();
  c.run.inputs = {(test::source_dir() / "config/examples/scenes/pavilion.json").string(),
                  (test::source_dir() / "config/examples/scenes/pavilion_fused.json").string()};
  Logger log(config::LogLevel::Error, config::LogFormat::Json, stderr);
  RunSummary summary;
  ASSERT_TRUE(run_embedded(c, log, summary).ok());
  const auto manifest = nlohmann::json::parse(test::read_file(summary.manifest));
  ASSERT_TRUE(manifest.contains("index"));
  const std::string bytes = test::read_file(summary.run_dir / "index.gpkg");
  EXPECT_EQ(manifest["index"]["key"], "index.gpkg");
  EXPECT_EQ(manifest["index"]["sha256"], sha256_hex(bytes));
  EXPECT_EQ(manifest["index"]["bytes"], bytes.size());
  // pavilion: eight primitives as a set, eight objects; pavilion_fused: one fused solid.
  EXPECT_EQ(manifest["index"]["objects"], 9);
  auto index = TopologyIndexReader::open(summary.run_dir / "index.gpkg");
  ASSERT_TRUE(index.ok());
  const auto ids =
      index.value()->sql("SELECT object_id, primitive_count FROM objects ORDER BY fid");
  ASSERT_TRUE(ids.ok());
  EXPECT_EQ(ids->front(), (std::vector<std::string>{"0-0", "1"}));
  EXPECT_EQ(ids->back(), (std::vector<std::string>{"1-0", "8"}));
  const auto columns = index.value()->sql(kObjectsTouching, {"0-0"});
  ASSERT_TRUE(columns.ok());
  EXPECT_FALSE(columns->empty());  // the first column carries the slab
  // A second run on the same queue writes the same index and the same manifest.
  const std::string before = test::read_file(summary.manifest);
  RunSummary again;
  ASSERT_TRUE(run_embedded(c, log, again).ok());
  EXPECT_EQ(test::read_file(again.manifest), before);
  EXPECT_EQ(test::read_file(again.run_dir / "index.gpkg"), bytes);
}

}  // namespace
}  // namespace csgtile::worker
