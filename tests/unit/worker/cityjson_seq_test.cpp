// The CityJSON text sequence: lines that parse back with the expected counts, closed and
// outward shells on the quantised vertices, roof / wall / ground semantics, polygons with
// holes, cavities, collapsed triangles, open shells written as MultiSurface, the same bytes
// for the same objects, the official CityJSON 2.0.2 schemas (ajv) and the run's output.

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "csgtile/geo/crs.h"
#include "csgtile/kernel/explorer.h"
#include "csgtile/kernel/mass_properties.h"
#include "csgtile/worker/publish.h"
#include "csgtile/worker/run.h"
#include "export/cityjson_seq.h"
#include "export/topology_index.h"
#include "index_object_builder.h"
#include "model_builders.h"
#include "test_commands.h"
#include "test_support.h"

namespace csgtile::worker {
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;
using kernel::ShapeKind;
using kernel::Vec3;

// ---- objects ---------------------------------------------------------------------------------

kernel::PrimitiveSpec box(Vec3 at, Vec3 size) { return test::box_at(at, size); }
kernel::PrimitiveSpec cylinder(Vec3 at, double r, double h) { return test::cylinder_at(at, r, h); }
using test::leaf;

kernel::CsgModel combine(const std::vector<kernel::CsgModel>& models, kernel::BooleanOp op) {
  auto m = kernel::csg_combine(models, op);
  EXPECT_TRUE(m.ok()) << m.error().message;
  return std::move(m).value();
}

IndexObject object(const std::string& id, kernel::CsgModel model) {
  return test::index_object(id, std::move(model));
}

// Two boxes fused with a cylinder through the top of the higher one; a plain box; a block
// drilled through (top and bottom with a hole); a box with a closed cavity.
std::vector<IndexObject> build_objects() {
  std::vector<IndexObject> out;
  out.push_back(object("fused", combine({leaf(box({0, 0, 0}, {2, 1, 1}), "a"),
                                         leaf(box({1, 0, 0}, {2, 1, 1.5}), "b"),
                                         leaf(cylinder({2.5, 0.5, 1}, 0.3, 1), "c")},
                                        kernel::BooleanOp::Fuse)));
  out[0].primitives[0].inliers = 100;
  out[0].primitives[0].rms = 0.01;
  out[0].primitives[0].coverage = 0.9;
  out[0].primitives[0].within_2sigma = 0.95;
  out.push_back(object("block", leaf(box({10, 0, 0}, {2, 3, 4}), "block")));
  out.push_back(object("drilled", combine({leaf(box({20, 0, 0}, {3, 2, 2}), "slab"),
                                           leaf(cylinder({21.5, 1, -1}, 0.5, 4), "bore")},
                                          kernel::BooleanOp::Cut)));
  out.push_back(object("hollow", combine({leaf(box({30, 0, 0}, {4, 4, 4}), "outer"),
                                          leaf(box({31, 1, 1}, {2, 2, 2}), "void")},
                                         kernel::BooleanOp::Cut)));
  add_building_lods(out, 0.01, 1e-7);
  return out;
}

const std::vector<IndexObject>& sample_objects() {
  static const std::vector<IndexObject> objects = build_objects();
  return objects;
}

// The Dutch frame of the README's example: RD New + NAP, a tile origin.
CityJsonOptions rd_options() {
  CityJsonOptions options;
  auto crs = geo::crs_from_config("EPSG:28992+5709");
  EXPECT_TRUE(crs.ok());
  options.crs = crs.value();
  options.origin = Vec3(155000, 463000, 2.5);
  return options;
}

// ---- reading the file back -------------------------------------------------------------------

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

struct Sequence {
  Json header;
  std::vector<Json> features;
};

Sequence parse(const std::string& text) {
  Sequence s;
  EXPECT_FALSE(text.empty());
  EXPECT_EQ(text.back(), '\n');
  const auto lines = lines_of(text);
  if (lines.empty()) return s;
  s.header = Json::parse(lines[0]);
  for (std::size_t i = 1; i < lines.size(); ++i) s.features.push_back(Json::parse(lines[i]));
  return s;
}

const Json& city_object(const Json& feature) {
  return feature["CityObjects"][feature["id"].get<std::string>()];
}

// The shells of a feature's geometry (a Solid's shells, or a MultiSurface as one "shell") with
// the semantic surface type of each surface.
struct FileShell {
  Json surfaces;                   ///< [surface][ring][vertex index]
  std::vector<std::string> types;  ///< semantic type per surface
};

std::vector<FileShell> shells_of(const Json& feature) {
  std::vector<FileShell> out;
  const Json& g = city_object(feature)["geometry"][0];
  const Json& names = g["semantics"]["surfaces"];
  auto add = [&](const Json& surfaces, const Json& values) {
    FileShell shell{surfaces, {}};
    for (const Json& v : values) shell.types.push_back(names[v.get<std::size_t>()]["type"]);
    out.push_back(std::move(shell));
  };
  if (g["type"] == "Solid") {
    for (std::size_t i = 0; i < g["boundaries"].size(); ++i)
      add(g["boundaries"][i], g["semantics"]["values"][i]);
  } else if (g["type"] == "MultiSurface") {
    add(g["boundaries"], g["semantics"]["values"]);
  }
  return out;
}

Vec3 vertex(const Json& feature, const Json& index, double scale) {
  const Json& v = feature["vertices"][index.get<std::size_t>()];
  return Vec3(v[0].get<double>(), v[1].get<double>(), v[2].get<double>()) * scale;
}

Vec3 ring_normal(const Json& feature, const Json& ring, double scale) {
  Vec3 n = Vec3::Zero();
  for (std::size_t i = 0; i < ring.size(); ++i) {
    n += vertex(feature, ring[i], scale).cross(vertex(feature, ring[(i + 1) % ring.size()], scale));
  }
  return n;
}

// Signed volume of a shell (fans of every ring, holes included), in model units.
double shell_volume(const Json& feature, const FileShell& shell, double scale) {
  double v = 0.0;
  for (const Json& surface : shell.surfaces) {
    for (const Json& ring : surface) {
      const Vec3 a = vertex(feature, ring[0], scale);
      for (std::size_t i = 1; i + 1 < ring.size(); ++i) {
        v += a.dot(vertex(feature, ring[i], scale).cross(vertex(feature, ring[i + 1], scale))) / 6;
      }
    }
  }
  return v;
}

// Closed and consistently oriented: each directed ring segment once, its reverse once.
bool shell_closed(const FileShell& shell) {
  std::map<std::pair<std::size_t, std::size_t>, int> segments;
  for (const Json& surface : shell.surfaces) {
    for (const Json& ring : surface) {
      for (std::size_t i = 0; i < ring.size(); ++i)
        ++segments[{ring[i].get<std::size_t>(), ring[(i + 1) % ring.size()].get<std::size_t>()}];
    }
  }
  for (const auto& [s, n] : segments) {
    const auto back = segments.find({s.second, s.first});
    if (n != 1 || back == segments.end() || back->second != 1) return false;
  }
  return !segments.empty();
}

Json surface_named(const Json& feature, const FileShell& shell, double scale, const Vec3& normal) {
  for (std::size_t i = 0; i < shell.surfaces.size(); ++i) {
    const Vec3 n = ring_normal(feature, shell.surfaces[i][0], scale).normalized();
    if (n.dot(normal) > 1 - 1e-9) return Json{{"type", shell.types[i]}, {"index", i}};
  }
  return Json();
}

class CityJsonSeqTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    auto text = cityjson_seq(sample_objects(), rd_options(), &stats_);
    ASSERT_TRUE(text.ok()) << text.error().message;
    text_ = new std::string(std::move(text).value());
    sequence_ = new Sequence(parse(*text_));
  }
  static void TearDownTestSuite() {
    delete text_;
    delete sequence_;
  }
  static const Json& feature(const std::string& id) {
    for (const Json& f : sequence_->features) {
      if (f["id"] == id) return f;
    }
    ADD_FAILURE() << "no feature " << id;
    static const Json none;
    return none;
  }
  static std::string* text_;
  static Sequence* sequence_;
  static CityJsonStats stats_;
};
std::string* CityJsonSeqTest::text_ = nullptr;
Sequence* CityJsonSeqTest::sequence_ = nullptr;
CityJsonStats CityJsonSeqTest::stats_;

constexpr double kScale = 0.001;

// ---- structure -------------------------------------------------------------------------------

TEST_F(CityJsonSeqTest, HeaderLineHasTransformCrsAndExtentAndNoObjects) {
  const Json& h = sequence_->header;
  EXPECT_EQ(h["type"], "CityJSON");
  EXPECT_EQ(h["version"], "2.0");
  EXPECT_EQ(h["transform"]["scale"], Json::array({0.001, 0.001, 0.001}));
  EXPECT_EQ(h["transform"]["translate"], Json::array({155000.0, 463000.0, 2.5}));
  EXPECT_TRUE(h["CityObjects"].is_object() && h["CityObjects"].empty());
  EXPECT_TRUE(h["vertices"].is_array() && h["vertices"].empty());
  EXPECT_EQ(h["metadata"]["referenceSystem"], "https://www.opengis.net/def/crs/EPSG/0/7415");
  // From the fused boxes' corner (0, 0, 0) to the hollow box's far corner (34, 4, 4).
  EXPECT_EQ(h["metadata"]["geographicalExtent"],
            Json::array({155000.0, 463000.0, 2.5, 155034.0, 463004.0, 6.5}));
  // Keys in the documented order.
  EXPECT_EQ(
      lines_of(*text_)[0].rfind("{\"type\":\"CityJSON\",\"version\":\"2.0\",\"transform\"", 0), 0u);
}

TEST_F(CityJsonSeqTest, OneFeaturePerObjectWithItsIdAttributesAndIntegerVertices) {
  ASSERT_EQ(sequence_->features.size(), sample_objects().size());
  EXPECT_EQ(stats_.features, sample_objects().size());
  EXPECT_EQ(stats_.open_objects, 0u);
  EXPECT_TRUE(stats_.warnings.empty());
  EXPECT_FALSE(sample_objects()[0].lod12.has_value());  // "fused": boxes and a cylinder
  EXPECT_TRUE(sample_objects()[1].lod12.has_value());   // "block": a box
  for (std::size_t i = 0; i < sample_objects().size(); ++i) {
    const IndexObject& o = sample_objects()[i];
    const Json& f = sequence_->features[i];
    EXPECT_EQ(f["type"], "CityJSONFeature");
    EXPECT_EQ(f["id"], o.id);
    ASSERT_EQ(f["CityObjects"].size(), 1u);
    const Json& co = city_object(f);
    EXPECT_EQ(co["type"], "Building");
    // Objects of boxes and extrusions are buildings: their model as lod 2.2, their LoD1.3
    // and their LoD1.2 block; the others (a cylinder among their primitives) one lod-2 solid.
    ASSERT_EQ(co["geometry"].size(), o.lod12 ? (o.lod13 ? 3u : 2u) : 1u) << o.id;
    EXPECT_EQ(co["geometry"][0]["type"], "Solid") << o.id;
    EXPECT_EQ(co["geometry"][0]["lod"], o.lod12 ? "2.2" : "2") << o.id;
    if (o.lod12) {
      EXPECT_EQ(co["geometry"][1]["lod"], o.lod13 ? "1.3" : "1.2") << o.id;
      EXPECT_EQ(co["geometry"].back()["lod"], "1.2") << o.id;
    }
    const Json& a = co["attributes"];
    EXPECT_EQ(a["primitive_count"], o.primitives.size());
    EXPECT_EQ(a["csg_nodes"], o.model.nodes.size());
    EXPECT_DOUBLE_EQ(a["volume"].get<double>(), kernel::mass_properties(o.model.shape).volume);
    EXPECT_EQ(a["valid"], true);
    EXPECT_EQ(a["closed"], true);
    EXPECT_FALSE(a.contains("collapsed_triangles"));
    // Vertices: integer triples, each used, none twice.
    std::set<std::vector<std::int64_t>> distinct;
    for (const Json& v : f["vertices"]) {
      ASSERT_EQ(v.size(), 3u);
      for (const Json& c : v) EXPECT_TRUE(c.is_number_integer());
      distinct.insert(v.get<std::vector<std::int64_t>>());
    }
    EXPECT_EQ(distinct.size(), f["vertices"].size()) << o.id;
    std::set<std::size_t> used;
    for (const FileShell& shell : shells_of(f)) {
      for (const Json& surface : shell.surfaces) {
        for (const Json& ring : surface) {
          for (const Json& v : ring) used.insert(v.get<std::size_t>());
        }
      }
    }
    EXPECT_EQ(used.size(), f["vertices"].size()) << o.id;
  }
  const Json& fused = city_object(feature("fused"))["attributes"];
  EXPECT_EQ(fused["primitive_types"], Json::array({"box", "cylinder"}));
  EXPECT_DOUBLE_EQ(fused["fit_rms"].get<double>(), 0.01);
  EXPECT_DOUBLE_EQ(fused["fit_coverage"].get<double>(), 0.9);
  EXPECT_DOUBLE_EQ(fused["fit_within_2sigma"].get<double>(), 0.95);
  EXPECT_FALSE(city_object(feature("block"))["attributes"].contains("fit_rms"));
}

TEST_F(CityJsonSeqTest, BuildingsCarryTheirGroundAndRoofHeights) {
  // The 2 × 3 × 4 box from z = 0 in a file whose origin is at 2.5 m: ground 2.5, roof 6.5.
  const Json& block = city_object(feature("block"))["attributes"];
  EXPECT_DOUBLE_EQ(block["h_ground"].get<double>(), 2.5);
  for (const char* key : {"h_roof_min", "h_roof_50p", "h_roof_70p", "h_roof_max"}) {
    EXPECT_DOUBLE_EQ(block[key].get<double>(), 6.5) << key;
  }
  EXPECT_EQ(block["roof_surfaces"], 1);
  for (const Json& f : sequence_->features) {
    const Json& a = city_object(f)["attributes"];
    ASSERT_TRUE(a.contains("h_roof_max")) << f["id"];
    EXPECT_LE(a["h_ground"].get<double>(), a["h_roof_min"].get<double>());
    EXPECT_LE(a["h_roof_min"].get<double>(), a["h_roof_50p"].get<double>());
    EXPECT_LE(a["h_roof_50p"].get<double>(), a["h_roof_70p"].get<double>());
    EXPECT_LE(a["h_roof_70p"].get<double>(), a["h_roof_max"].get<double>());
  }
}

// ---- geometry --------------------------------------------------------------------------------

TEST_F(CityJsonSeqTest, ShellsAreClosedAndOutwardOnTheQuantisedVertices) {
  for (const IndexObject& o : sample_objects()) {
    const Json& f = feature(o.id);
    const auto shells = shells_of(f);
    ASSERT_FALSE(shells.empty()) << o.id;
    double total = 0.0;
    for (std::size_t s = 0; s < shells.size(); ++s) {
      EXPECT_TRUE(shell_closed(shells[s])) << o.id << " shell " << s;
      const double v = shell_volume(f, shells[s], kScale);
      // The exterior shell first and enclosing; cavities face into their voids.
      if (s == 0) {
        EXPECT_GT(v, 0.0) << o.id;
      } else {
        EXPECT_LT(v, 0.0) << o.id;
      }
      total += v;
    }
    // Planar solids are exact; curved faces are inscribed within the chordal tolerance.
    const double exact = kernel::mass_properties(o.model.shape).volume;
    const bool curved = f.dump().find("cylinder") != std::string::npos;
    EXPECT_NEAR(total, exact, curved ? 0.05 * exact : 1e-9) << o.id;
  }
  // The hollow box: a 4 m cube around a 2 m cavity.
  const auto hollow = shells_of(feature("hollow"));
  ASSERT_EQ(hollow.size(), 2u);
  EXPECT_NEAR(shell_volume(feature("hollow"), hollow[0], kScale), 64.0, 1e-9);
  EXPECT_NEAR(shell_volume(feature("hollow"), hollow[1], kScale), -8.0, 1e-9);
}

TEST_F(CityJsonSeqTest, BoxTopIsRoofBottomIsGroundSidesAreWalls) {
  const Json& f = feature("block");
  const auto shells = shells_of(f);
  ASSERT_EQ(shells.size(), 1u);
  ASSERT_EQ(shells[0].surfaces.size(), 6u);  // planar faces: one polygon each
  EXPECT_EQ(surface_named(f, shells[0], kScale, Vec3::UnitZ())["type"], "RoofSurface");
  EXPECT_EQ(surface_named(f, shells[0], kScale, -Vec3::UnitZ())["type"], "GroundSurface");
  const std::vector<Vec3> sides = {Vec3(1, 0, 0), Vec3(-1, 0, 0), Vec3(0, 1, 0), Vec3(0, -1, 0)};
  for (const Vec3& side : sides) {
    EXPECT_EQ(surface_named(f, shells[0], kScale, side)["type"], "WallSurface") << side.transpose();
  }
  // Only the used semantic surfaces, in the order roof, wall, ground.
  EXPECT_EQ(
      city_object(f)["geometry"][0]["semantics"]["surfaces"],
      Json::parse(R"([{"type":"RoofSurface"},{"type":"WallSurface"},{"type":"GroundSurface"}])"));
}

TEST_F(CityJsonSeqTest, UpwardFacesAboveGroundAreRoofsDownwardOnesAtTheBottomGround) {
  const Json& f = feature("fused");
  const FileShell shell = shells_of(f)[0];
  int roofs_at_1 = 0, grounds = 0;
  for (std::size_t i = 0; i < shell.surfaces.size(); ++i) {
    const Json& ring = shell.surfaces[i][0];
    const Vec3 n = ring_normal(f, ring, kScale).normalized();
    double top = -1e300;
    for (const Json& v : ring) top = std::max(top, vertex(f, v, kScale).z());
    if (n.z() > 0.999 && std::abs(top - 1.0) < 1e-9) {  // the lower box's top, beside the step
      EXPECT_EQ(shell.types[i], "RoofSurface");
      ++roofs_at_1;
    }
    if (shell.types[i] == "GroundSurface") {
      EXPECT_LT(n.z(), -0.9);
      EXPECT_NEAR(top, 0.0, 1e-9);
      ++grounds;
    }
    if (std::abs(n.z()) < 1e-9) {
      EXPECT_EQ(shell.types[i], "WallSurface");
    }
  }
  EXPECT_EQ(roofs_at_1, 1);
  EXPECT_EQ(grounds, 1);  // the two boxes' bottoms are one merged face
}

TEST_F(CityJsonSeqTest, PlanarFacesWithHolesArePolygonsWithInnerRings) {
  const Json& f = feature("drilled");
  const FileShell shell = shells_of(f)[0];
  int with_hole = 0;
  for (const Json& surface : shell.surfaces) {
    if (surface.size() != 2) continue;
    ++with_hole;
    const Vec3 outer = ring_normal(f, surface[0], kScale);
    const Vec3 inner = ring_normal(f, surface[1], kScale);
    EXPECT_LT(outer.dot(inner), 0.0);  // the hole runs the other way round
    EXPECT_GT(std::abs(outer.normalized().z()), 0.999);
  }
  EXPECT_EQ(with_hole, 2);  // top and bottom
}

TEST(CityJsonSeq, TrianglesThatCollapseAfterQuantisationAreLeftOutAndCounted) {
  // A 2 cm pipe quantised to 5 mm: neighbouring points of its circles meet.
  const std::vector<IndexObject> pipe = {
      object("pipe", leaf(cylinder({0, 0, 0}, 0.01, 1), "pipe"))};
  CityJsonOptions options;
  options.scale = 0.005;
  options.chordal_tolerance = 0.0001;
  CityJsonStats stats;
  const auto text = cityjson_seq(pipe, options, &stats);
  ASSERT_TRUE(text.ok()) << text.error().message;
  EXPECT_GT(stats.collapsed_triangles, 0u);
  const Sequence s = parse(text.value());
  ASSERT_EQ(s.features.size(), 1u);
  const Json& f = s.features[0];
  EXPECT_EQ(city_object(f)["attributes"]["collapsed_triangles"], stats.collapsed_triangles);
  // No surface repeats a vertex; the shell is still closed, or it says it is not.
  for (const FileShell& shell : shells_of(f)) {
    for (const Json& surface : shell.surfaces) {
      for (const Json& ring : surface) {
        const auto ids = ring.get<std::vector<std::size_t>>();
        EXPECT_EQ(std::set<std::size_t>(ids.begin(), ids.end()).size(), ids.size());
        EXPECT_GE(ids.size(), 3u);
      }
    }
    const bool closed = city_object(f)["attributes"]["closed"].get<bool>();
    EXPECT_EQ(shell_closed(shell), closed);
    EXPECT_EQ(city_object(f)["geometry"][0]["type"], closed ? "Solid" : "MultiSurface");
  }
}

// Validators snap vertices closer than their tolerance (val3dity: 1 mm, the default scale's
// unit): two distinct vertices a unit apart read as a repeated point (102) and a triangle on a
// line as a collapsed ring (104). The writer welds vertices within a unit of each other and
// absorbs flattened triangles into their neighbours; shells stay closed.
TEST(CityJsonSeq, NoTwoVerticesWithinAUnitAndNoTriangleOnALine) {
  // Fitted parts of one building standing 0.6 mm apart (their bases and tops), and a pipe
  // through them: at 1 mm, the steps' vertices are a unit apart.
  const std::vector<IndexObject> parts = {
      object("parts", combine({leaf(box({0, 0, 0}, {1, 1, 1}), "a"),
                               leaf(box({0.5, 0.5, 0.0006}, {1, 1, 0.9998}), "b"),
                               leaf(cylinder({0.25, 0.25, 0.0003}, 0.1, 1.2), "c")},
                              kernel::BooleanOp::Fuse))};
  CityJsonOptions options;
  options.scale = 0.001;
  options.chordal_tolerance = 0.0001;
  CityJsonStats stats;
  const auto text = cityjson_seq(parts, options, &stats);
  ASSERT_TRUE(text.ok()) << text.error().message;
  const Sequence s = parse(text.value());
  ASSERT_EQ(s.features.size(), 1u);
  const Json& f = s.features[0];
  const auto vertices = f["vertices"].get<std::vector<std::array<long long, 3>>>();
  std::size_t near_pairs = 0;
  for (std::size_t i = 0; i < vertices.size(); ++i) {
    for (std::size_t j = i + 1; j < vertices.size(); ++j) {
      near_pairs += std::abs(vertices[i][0] - vertices[j][0]) <= 1 &&
                    std::abs(vertices[i][1] - vertices[j][1]) <= 1 &&
                    std::abs(vertices[i][2] - vertices[j][2]) <= 1;
    }
  }
  EXPECT_EQ(near_pairs, 0u);
  for (const FileShell& shell : shells_of(f)) {
    for (const Json& surface : shell.surfaces) {
      const auto ring = surface[0].get<std::vector<std::size_t>>();
      if (ring.size() != 3) continue;
      const auto& a = vertices[ring[0]];
      const auto& b = vertices[ring[1]];
      const auto& c = vertices[ring[2]];
      const long long u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
      const long long v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
      const bool on_a_line = u[1] * v[2] - u[2] * v[1] == 0 && u[2] * v[0] - u[0] * v[2] == 0 &&
                             u[0] * v[1] - u[1] * v[0] == 0;
      EXPECT_FALSE(on_a_line) << "a triangle on a line";
    }
    EXPECT_TRUE(shell_closed(shell));
  }
  EXPECT_TRUE(city_object(f)["attributes"]["closed"].get<bool>());
  EXPECT_EQ(city_object(f)["geometry"][0]["type"], "Solid");
}

// val3dity triangulates each polygon and compares its triangles' normals (20°): a polygon
// with a feature of a few units (a 3 mm edge, at 1 mm) has a triangle that thin, turned by
// the rounding of its corners. Such faces are published as their triangles (a roof part of
// a real Delft building had a hole with a 2.8 mm edge: NON_PLANAR_POLYGON_NORMALS_DEVIATION).
TEST(CityJsonSeq, PolygonsWithFeaturesOfAFewUnitsArePublishedAsTriangles) {
  kernel::PrimitiveSpec notch;
  notch.type = kernel::PrimitiveType::Extrusion;
  notch.profile = {{0, 0}, {4, 0}, {4, 3}, {2.003, 3.5}, {2.0, 3.5}, {0, 3}};
  notch.height = 2.0;
  const std::vector<IndexObject> objects = {object("notch", leaf(notch, "notch"))};
  CityJsonOptions options;
  options.scale = 0.001;
  const auto text = cityjson_seq(objects, options, nullptr);
  ASSERT_TRUE(text.ok()) << text.error().message;
  const Sequence s = parse(text.value());
  ASSERT_EQ(s.features.size(), 1u);
  const Json& f = s.features[0];
  const auto vertices = f["vertices"].get<std::vector<std::array<long long, 3>>>();
  std::size_t triangles = 0, polygons = 0;
  for (const FileShell& shell : shells_of(f)) {
    EXPECT_TRUE(shell_closed(shell));
    for (const Json& surface : shell.surfaces) {
      const auto ring = surface[0].get<std::vector<std::size_t>>();
      if (ring.size() == 3) {
        ++triangles;
        continue;
      }
      ++polygons;
      for (std::size_t i = 0; i < ring.size(); ++i) {
        const auto& a = vertices[ring[i]];
        const auto& b = vertices[ring[(i + 1) % ring.size()]];
        const double length =
            std::hypot(static_cast<double>(a[0] - b[0]), static_cast<double>(a[1] - b[1]),
                       static_cast<double>(a[2] - b[2]));
        EXPECT_GE(length, 10.0) << "a polygon with an edge of " << length << " units";
      }
    }
  }
  EXPECT_GE(triangles, 8u);  // top and bottom, four triangles each at least
  EXPECT_EQ(polygons, 5u);   // the walls but the 3 mm one (a thin rectangle: triangles)
  EXPECT_EQ(city_object(f)["geometry"][0]["type"], "Solid");
}

// A tilted disc drawn finer than the units hold is published as its triangles. A cone fitted
// to a tree in a tile in feet: its base, 0.8 units in radius, drawn at the 2.4° steps its
// 20-unit top needs, has ears under one unit high; as one polygon, val3dity's triangulation
// kept them, the rounding turned their normals 30° apart (NON_PLANAR_POLYGON_NORMALS_DEVIATION)
// and the building was invalid. Upright, the disc's points share one height and it stays one
// polygon; so does the top, drawn by the chordal tolerance (ears of about ten units).
TEST(CityJsonSeq, TiltedDiscsDrawnFinerThanTheUnitsArePublishedAsTriangles) {
  const auto cone = [](const kernel::Location& at) {
    kernel::PrimitiveSpec spec;
    spec.type = kernel::PrimitiveType::Cone;
    spec.radius = 0.8;
    spec.radius2 = 20.0;
    spec.height = 10.0;
    spec.placement = at;
    return spec;
  };
  const kernel::Location level = kernel::Location::translation({3.0, 2.0, 1.0});
  const kernel::Location tilted =
      level * kernel::Location::rotation(Vec3::Zero(), Vec3(1.0, 0.5, 0.0), 0.35);
  CityJsonOptions options;
  options.scale = 0.001;
  // The polygons (more than three points) of the published cone, and their thinnest ear (a
  // point's distance to the chord of its neighbours), in units.
  const auto polygons_of = [&](const kernel::PrimitiveSpec& spec, std::size_t& polygons,
                               double& thinnest_ear) {
    const std::vector<IndexObject> objects = {object("c", leaf(spec, "c"))};
    const auto text = cityjson_seq(objects, options, nullptr);
    ASSERT_TRUE(text.ok()) << text.error().message;
    const Sequence s = parse(text.value());
    ASSERT_EQ(s.features.size(), 1u);
    const auto vertices = s.features[0]["vertices"].get<std::vector<std::array<long long, 3>>>();
    polygons = 0;
    thinnest_ear = INFINITY;
    for (const FileShell& shell : shells_of(s.features[0])) {
      EXPECT_TRUE(shell_closed(shell));
      for (const Json& surface : shell.surfaces) {
        const auto ring = surface[0].get<std::vector<std::size_t>>();
        if (ring.size() == 3) continue;
        ++polygons;
        const auto at = [&](std::size_t i) {
          const auto& v = vertices[ring[i % ring.size()]];
          return Vec3(static_cast<double>(v[0]), static_cast<double>(v[1]),
                      static_cast<double>(v[2]));
        };
        for (std::size_t i = 0; i < ring.size(); ++i) {
          const Vec3 a = at(i + ring.size() - 1), b = at(i), c = at(i + 1);
          thinnest_ear = std::min(thinnest_ear, (b - a).cross(c - a).norm() / (c - a).norm());
        }
      }
    }
  };
  std::size_t polygons = 0;
  double ear = 0.0;
  polygons_of(cone(tilted), polygons, ear);
  EXPECT_EQ(polygons, 1u);  // the top
  EXPECT_GE(ear, 5.0);
  polygons_of(cone(level), polygons, ear);
  EXPECT_EQ(polygons, 2u);  // level discs: one height, nothing to turn
}

// Where welding would open a shell (a thin pipe whose opposite sides are a unit apart), the
// object is written unwelded, still a closed solid, and without triangles on a line.
TEST(CityJsonSeq, WeldingNeverOpensAClosedShell) {
  const std::vector<IndexObject> pipes = {
      object("pipes", combine({leaf(cylinder({0, 0, 0}, 0.05, 1), "a"),
                               leaf(cylinder({0.049, 0.0, 0.3}, 0.03, 1), "b")},
                              kernel::BooleanOp::Fuse))};
  CityJsonOptions options;
  options.scale = 0.001;
  options.chordal_tolerance = 0.00002;
  const auto text = cityjson_seq(pipes, options, nullptr);
  ASSERT_TRUE(text.ok()) << text.error().message;
  const Sequence s = parse(text.value());
  ASSERT_EQ(s.features.size(), 1u);
  const Json& f = s.features[0];
  for (const FileShell& shell : shells_of(f)) EXPECT_TRUE(shell_closed(shell));
  EXPECT_EQ(city_object(f)["geometry"][0]["type"], "Solid");
}

TEST(CityJsonSeq, OpenShellIsWrittenAsMultiSurfaceAndReported) {
  // A box without its top face: a solid the kernel can hold but that encloses nothing.
  const auto boxed = kernel::csg_primitive(box({0, 0, 0}, {1, 1, 1}));
  ASSERT_TRUE(boxed.ok());
  std::vector<kernel::Shape> faces;
  const kernel::ShapeIndex box_faces = kernel::map_child_shapes(boxed->shape, ShapeKind::Face);
  for (const kernel::Shape& face : box_faces.shapes()) {
    if (kernel::mass_properties(face).bounds.min.z() < 0.5) faces.push_back(face);
  }
  ASSERT_EQ(faces.size(), 5u);
  auto shell = kernel::ShapeFactory::shell(faces);
  ASSERT_TRUE(shell.ok()) << shell.error().message;
  auto solid = kernel::ShapeFactory::solid({shell.value()});
  ASSERT_TRUE(solid.ok()) << solid.error().message;
  IndexObject open;
  open.id = "open";
  open.model.shape = solid.value();
  CityJsonStats stats;
  const auto text = cityjson_seq({open}, {}, &stats);
  ASSERT_TRUE(text.ok()) << text.error().message;
  EXPECT_EQ(stats.open_objects, 1u);
  ASSERT_EQ(stats.warnings.size(), 1u);
  EXPECT_NE(stats.warnings[0].find("open"), std::string::npos);
  const Sequence s = parse(text.value());
  const Json& co = city_object(s.features.at(0));
  EXPECT_EQ(co["geometry"][0]["type"], "MultiSurface");
  EXPECT_EQ(co["geometry"][0]["boundaries"].size(), 5u);
  EXPECT_EQ(co["attributes"]["closed"], false);
  // Without a CRS: no referenceSystem, translate zero.
  EXPECT_FALSE(s.header["metadata"].contains("referenceSystem"));
  EXPECT_EQ(s.header["transform"]["translate"], Json::array({0.0, 0.0, 0.0}));
}

TEST(CityJsonSeq, ObjectOfSeveralSolidsIsAGenericCityObjectWithAMultiSolid) {
  // An unfused group (its fuse failed) is a compound of solids; CityJSON's Building admits no
  // MultiSolid, so the object becomes a GenericCityObject.
  const auto a = kernel::csg_primitive(box({0, 0, 0}, {1, 1, 1}));
  const auto b = kernel::csg_primitive(box({3, 0, 0}, {1, 1, 2}));
  ASSERT_TRUE(a.ok() && b.ok());
  auto both = kernel::ShapeFactory::compound({a->shape, b->shape});
  ASSERT_TRUE(both.ok()) << both.error().message;
  IndexObject group;
  group.id = "group";
  group.model.shape = both.value();
  const auto text = cityjson_seq({group});
  ASSERT_TRUE(text.ok()) << text.error().message;
  const Sequence s = parse(text.value());
  const Json& co = city_object(s.features.at(0));
  EXPECT_EQ(co["type"], "GenericCityObject");
  EXPECT_EQ(co["geometry"][0]["type"], "MultiSolid");
  EXPECT_EQ(co["geometry"][0]["boundaries"].size(), 2u);
}

// ---- determinism, CRS, errors ----------------------------------------------------------------

TEST_F(CityJsonSeqTest, SameObjectsGiveTheSameBytes) {
  const auto again = cityjson_seq(sample_objects(), rd_options());
  ASSERT_TRUE(again.ok());
  EXPECT_EQ(again.value(), *text_);
  // Objects built anew (other pointers, other hash orders) give the same bytes too.
  const auto rebuilt = cityjson_seq(build_objects(), rd_options());
  ASSERT_TRUE(rebuilt.ok());
  EXPECT_EQ(rebuilt.value(), *text_);
}

TEST(CityJsonSeq, ReferenceSystemNamesTheCompoundCodeWhenEpsgHasOne) {
  auto url = [](const char* text, std::vector<std::string>* warnings = nullptr) {
    const auto crs = geo::crs_from_config(text);
    EXPECT_TRUE(crs.ok()) << text;
    return cityjson_reference_system(crs.value(), warnings);
  };
  const std::string base = "https://www.opengis.net/def/crs/EPSG/0/";
  EXPECT_EQ(url("EPSG:28992+5709"), base + "7415");
  EXPECT_EQ(url("EPSG:7415"), base + "7415");
  EXPECT_EQ(url("EPSG:28992"), base + "28992");
  EXPECT_EQ(url("EPSG:4979"), base + "4979");
  std::vector<std::string> warnings;
  EXPECT_EQ(url("EPSG:25832+5941", &warnings), base + "25832");
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].find("25832+5941"), std::string::npos);
}

TEST(CityJsonSeq, BadOptionsAndObjectsAreNamedErrors) {
  const IndexObject block = object("b", leaf(box({0, 0, 0}, {1, 1, 1}), "b"));
  CityJsonOptions zero_scale;
  zero_scale.scale = 0.0;
  auto r = cityjson_seq({block}, zero_scale);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().code, ErrorCode::InputInvalid);
  r = cityjson_seq({block, block});
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("duplicate id \"b\""), std::string::npos);
  IndexObject empty;
  empty.id = "nothing";
  r = cityjson_seq({empty});
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("nothing"), std::string::npos);
  // No objects: a header line only.
  r = cityjson_seq({});
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(lines_of(r.value()).size(), 1u);
}

// ---- the official schemas (ajv) --------------------------------------------------------------

using test::CommandResult;
using test::quoted;
CommandResult run_command(const std::string& command) { return test::run_command(command, true); }

fs::path schema_dir() { return test::shared_dir() / "schemas" / "cityjson-2.0.2"; }

// ajv-cli: $CSGTILE_AJV, else the build directory's npm install (deploy/run-tests.sh:
// `npm install --prefix build/npm ajv@8 ajv-formats@3 ajv-cli@5`).
fs::path ajv_path() {
  if (const char* env = std::getenv("CSGTILE_AJV"); env != nullptr && *env != '\0') return env;
  return CSGTILE_AJV;
}

// Without ajv the schema checks skip, unless CSGTILE_REQUIRE_AJV=1 makes its absence a failure
// (CI). Without the schemas (../shared/schemas) they skip.
#define REQUIRE_AJV_AND_SCHEMAS()                                                              \
  do {                                                                                         \
    if (!fs::exists(schema_dir() / "cityjson.min.schema.json")) {                              \
      GTEST_SKIP() << "CityJSON 2.0.2 schemas not found in " << schema_dir();                  \
    }                                                                                          \
    if (!fs::exists(ajv_path())) {                                                             \
      const std::string why_ = "ajv not found at " + ajv_path().string() +                     \
                               " (set CSGTILE_AJV, or npm install --prefix <build>/npm ajv@8 " \
                               "ajv-formats@3 ajv-cli@5 as deploy/run-tests.sh does)";         \
      const char* require_ = std::getenv("CSGTILE_REQUIRE_AJV");                               \
      if (require_ != nullptr && std::string(require_) == "1") FAIL() << why_;                 \
      GTEST_SKIP() << why_;                                                                    \
    }                                                                                          \
  } while (false)

// ajv-cli on `files` against one of the schemas. The .min schemas are self-contained (the
// others would need their referenced files passed with -r).
CommandResult ajv_validate(const std::string& schema, const std::vector<fs::path>& files) {
  std::string command = quoted(ajv_path()) +
                        " validate --spec=draft7 -c ajv-formats --strict=false -s " +
                        quoted(schema_dir() / schema);
  for (const fs::path& f : files) command += " -d " + quoted(f);
  return run_command(command);
}

// Line 1 against cityjson.min.schema.json, every other line against
// cityjsonfeature.min.schema.json (one ajv run per schema).
CommandResult validate_with_ajv(const std::string& text, const fs::path& dir) {
  const auto lines = lines_of(text);
  std::vector<fs::path> features;
  for (std::size_t i = 0; i < lines.size(); ++i) {
    const fs::path file = dir / ("line" + std::to_string(i) + ".json");
    std::ofstream(file, std::ios::binary) << lines[i] << '\n';
    if (i > 0) features.push_back(file);
  }
  CommandResult header = ajv_validate("cityjson.min.schema.json", {dir / "line0.json"});
  if (header.exit_code != 0 || features.empty()) return header;
  CommandResult rest = ajv_validate("cityjsonfeature.min.schema.json", features);
  rest.out = header.out + rest.out;
  return rest;
}

TEST_F(CityJsonSeqTest, AjvAcceptsTheHeaderAndEveryFeature) {
  REQUIRE_AJV_AND_SCHEMAS();
  test::TempDir dir("csgtile-cityjson-ajv-");
  const CommandResult r = validate_with_ajv(*text_, dir.path());
  EXPECT_EQ(r.exit_code, 0) << r.out;
  // One "valid" line per file.
  std::size_t valid = 0;
  for (std::size_t at = r.out.find(" valid"); at != std::string::npos;
       at = r.out.find(" valid", at + 1))
    ++valid;
  EXPECT_EQ(valid, sample_objects().size() + 1) << r.out;
}

TEST(CityJsonSeq, AjvRejectsAFeatureThatBreaksTheSchema) {
  REQUIRE_AJV_AND_SCHEMAS();
  test::TempDir dir("csgtile-cityjson-ajv-bad-");
  const auto text = cityjson_seq({object("b", leaf(box({0, 0, 0}, {1, 1, 1}), "b"))});
  ASSERT_TRUE(text.ok());
  // The validator is live: a numeric lod is not CityJSON.
  std::string feature = lines_of(text.value()).at(1);
  const std::size_t at = feature.find("\"lod\":\"2\"");
  ASSERT_NE(at, std::string::npos);
  feature.replace(at, 9, "\"lod\":2");
  const fs::path file = dir / "broken.json";
  std::ofstream(file, std::ios::binary) << feature << '\n';
  const CommandResult r = ajv_validate("cityjsonfeature.min.schema.json", {file});
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.out.find("broken.json invalid"), std::string::npos) << r.out;
}

// ---- the run ---------------------------------------------------------------------------------

TEST(CityJsonRun, RunPublishesTheSequenceWithTheIndexIdsAndNamesItInTheManifest) {
  test::TempDir dir("csgtile-run-cityjson-");
  config::Config c;
  c.run.name = "t";
  c.run.output = (dir / "out").string();
  c.run.inputs = {(test::source_dir() / "config/examples/scenes/pavilion.json").string(),
                  (test::source_dir() / "config/examples/scenes/pavilion_fused.json").string()};
  Logger log(config::LogLevel::Error, config::LogFormat::Json, stderr);
  RunSummary summary;
  ASSERT_TRUE(run_embedded(c, log, summary).ok());
  const auto manifest = Json::parse(test::read_file(summary.manifest));
  ASSERT_TRUE(manifest.contains("cityjson"));
  const std::string bytes = test::read_file(summary.run_dir / "model.city.jsonl");
  EXPECT_EQ(manifest["cityjson"]["key"], "model.city.jsonl");
  EXPECT_EQ(manifest["cityjson"]["sha256"], sha256_hex(bytes));
  EXPECT_EQ(manifest["cityjson"]["bytes"], bytes.size());
  EXPECT_EQ(manifest["cityjson"]["features"], manifest["index"]["objects"]);
  // The features carry the index's object ids, in its order.
  auto index = TopologyIndexReader::open(summary.run_dir / "index.gpkg");
  ASSERT_TRUE(index.ok());
  const auto ids = index.value()->sql("SELECT object_id FROM objects ORDER BY fid");
  ASSERT_TRUE(ids.ok());
  const Sequence s = parse(bytes);
  ASSERT_EQ(s.features.size(), ids->size());
  for (std::size_t i = 0; i < ids->size(); ++i) EXPECT_EQ(s.features[i]["id"], (*ids)[i][0]);
  for (const Json& f : s.features) EXPECT_EQ(city_object(f)["attributes"]["closed"], true);
  // A second run writes the same bytes.
  RunSummary again;
  ASSERT_TRUE(run_embedded(c, log, again).ok());
  EXPECT_EQ(test::read_file(again.run_dir / "model.city.jsonl"), bytes);
}

TEST(CityJsonRun, ScenesInOneCrsGiveItsReferenceSystemAndTheirOrigins) {
  test::TempDir dir("csgtile-run-cityjson-crs-");
  // Two one-box scenes in RD New + NAP, 100 m apart.
  auto write_scene = [&](const std::string& name, double x) {
    const fs::path path = dir / (name + ".json");
    std::ofstream(path) << R"({"name":")" << name << R"(","crs":"EPSG:28992+5709","origin":[)" << x
                        << R"(,463000,1.25],"primitives":[{"type":"box","id":"b","size":[2,2,3],)"
                        << R"("placement":[[1,0,0,0],[0,1,0,0],[0,0,1,0]]}]})";
    return path.string();
  };
  config::Config c;
  c.run.name = "rd";
  c.run.output = (dir / "out").string();
  c.run.inputs = {write_scene("west", 155000), write_scene("east", 155100)};
  Logger log(config::LogLevel::Error, config::LogFormat::Json, stderr);
  RunSummary summary;
  ASSERT_TRUE(run_embedded(c, log, summary).ok());
  const Sequence s = parse(test::read_file(summary.run_dir / "model.city.jsonl"));
  EXPECT_EQ(s.header["metadata"]["referenceSystem"], "https://www.opengis.net/def/crs/EPSG/0/7415");
  EXPECT_EQ(s.header["transform"]["translate"], Json::array({155000.0, 463000.0, 1.25}));
  EXPECT_EQ(s.header["metadata"]["geographicalExtent"],
            Json::array({155000.0, 463000.0, 1.25, 155102.0, 463002.0, 4.25}));
  ASSERT_EQ(s.features.size(), 2u);
  // The east box sits 100 m (100 000 units) east of the west one.
  auto min_x = [](const Json& f) {
    std::int64_t m = INT64_MAX;
    for (const Json& v : f["vertices"]) m = std::min(m, v[0].get<std::int64_t>());
    return m;
  };
  EXPECT_EQ(min_x(s.features[0]), 0);
  EXPECT_EQ(min_x(s.features[1]), 100000);
}

}  // namespace
}  // namespace csgtile::worker
