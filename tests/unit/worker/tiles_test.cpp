// 3D Tiles: the glTF binary parsed back (header, chunks, alignment, accessors against the
// buffer, feature ids, the property table), geometry (closed and outward per object, y up,
// flat faces with flat normals), the same bytes for the same objects, the ENU → ECEF
// transform against PROJ's cs2cs, regions that hold their boxes, the Khronos glTF validator
// (npm gltf-validator) and the run's output.

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <bit>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <numbers>
#include <set>
#include <sstream>

#include "csgtile/geo/crs.h"
#include "csgtile/geo/georeference.h"
#include "csgtile/kernel/check.h"
#include "csgtile/kernel/mass_properties.h"
#include "csgtile/worker/publish.h"
#include "csgtile/worker/run.h"
#include "export/gltf_writer.h"
#include "export/tile_content.h"
#include "export/tileset.h"
#include "export/topology_index.h"
#include "index_object_builder.h"
#include "model_builders.h"
#include "test_commands.h"
#include "test_support.h"

namespace csgtile::worker {
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;
using kernel::Vec3;

// ---- objects ---------------------------------------------------------------------------------

kernel::PrimitiveSpec box(Vec3 at, Vec3 size) { return test::box_at(at, size); }
kernel::PrimitiveSpec cylinder(Vec3 at, double r, double h) { return test::cylinder_at(at, r, h); }
using test::leaf;

IndexObject object(const std::string& id, kernel::CsgModel model) {
  return test::index_object(id, std::move(model));
}

// A box, a cylinder, and a box fused with a cylinder standing on it.
std::vector<IndexObject> build_objects() {
  std::vector<IndexObject> out;
  out.push_back(object("block", leaf(box({0, 0, 0}, {2, 3, 4}), "block")));
  out.push_back(object("tower", leaf(cylinder({10, 0, 0}, 1.5, 6), "tower")));
  auto fused = kernel::csg_combine(
      {leaf(box({20, 0, 0}, {4, 2, 1}), "base"), leaf(cylinder({22, 1, 1}, 0.5, 2), "mast")},
      kernel::BooleanOp::Fuse);
  EXPECT_TRUE(fused.ok()) << fused.error().message;
  out.push_back(object("fused", std::move(fused).value()));
  return out;
}

const std::vector<IndexObject>& sample_objects() {
  static const std::vector<IndexObject> objects = build_objects();
  return objects;
}

// ---- reading a GLB back ----------------------------------------------------------------------

std::uint32_t u32_at(const std::string& b, std::size_t at) {
  std::uint32_t v = 0;
  for (int i = 3; i >= 0; --i) v = (v << 8) | static_cast<unsigned char>(b.at(at + i));
  return v;
}
float f32_at(const std::string& b, std::size_t at) { return std::bit_cast<float>(u32_at(b, at)); }
double f64_at(const std::string& b, std::size_t at) {
  const std::uint64_t v = (std::uint64_t{u32_at(b, at + 4)} << 32) | u32_at(b, at);
  return std::bit_cast<double>(v);
}

struct Glb {
  Json json;
  std::string bin;
};

// The GLB container checked on the way: magic, version, length, two chunks (JSON then BIN),
// each a multiple of 4 bytes, the JSON padded with spaces.
Glb parse_glb(const std::string& bytes) {
  Glb glb;
  EXPECT_GE(bytes.size(), 28u);
  if (bytes.size() < 28) return glb;
  EXPECT_EQ(bytes.substr(0, 4), "glTF");
  EXPECT_EQ(u32_at(bytes, 4), 2u);
  EXPECT_EQ(u32_at(bytes, 8), bytes.size());
  const std::uint32_t json_length = u32_at(bytes, 12);
  EXPECT_EQ(u32_at(bytes, 16), 0x4E4F534Au);  // "JSON"
  EXPECT_EQ(json_length % 4, 0u);
  const std::string json = bytes.substr(20, json_length);
  const std::size_t bin_at = 20 + json_length;
  EXPECT_EQ(u32_at(bytes, bin_at + 4), 0x004E4942u);  // "BIN\0"
  const std::uint32_t bin_length = u32_at(bytes, bin_at);
  EXPECT_EQ(bin_length % 4, 0u);
  EXPECT_EQ(bin_at + 8 + bin_length, bytes.size());
  glb.json = Json::parse(json);  // trailing spaces are JSON whitespace
  EXPECT_EQ(json.find_last_not_of(' ') + 1, json.find_last_of('}') + 1);
  glb.bin = bytes.substr(bin_at + 8, bin_length);
  return glb;
}

// Byte offset and element count of an accessor, its view checked against the buffer.
std::pair<std::size_t, std::size_t> accessor_span(const Glb& glb, std::size_t index,
                                                  std::size_t element_bytes) {
  const Json& a = glb.json["accessors"][index];
  const Json& view = glb.json["bufferViews"][a["bufferView"].get<std::size_t>()];
  const std::size_t at = view["byteOffset"].get<std::size_t>() + a.value("byteOffset", 0u);
  const std::size_t count = a["count"];
  EXPECT_LE(count * element_bytes, view["byteLength"].get<std::size_t>());
  EXPECT_LE(view["byteOffset"].get<std::size_t>() + view["byteLength"].get<std::size_t>(),
            glb.bin.size());
  EXPECT_EQ(at % 4, 0u);
  return {at, count};
}

std::vector<std::array<float, 3>> vec3_accessor(const Glb& glb, std::size_t index) {
  EXPECT_EQ(glb.json["accessors"][index]["type"], "VEC3");
  EXPECT_EQ(glb.json["accessors"][index]["componentType"], 5126);
  const auto [at, count] = accessor_span(glb, index, 12);
  std::vector<std::array<float, 3>> out(count);
  for (std::size_t i = 0; i < count; ++i) {
    for (std::size_t k = 0; k < 3; ++k) out[i][k] = f32_at(glb.bin, at + 12 * i + 4 * k);
  }
  return out;
}

std::vector<float> float_accessor(const Glb& glb, std::size_t index) {
  EXPECT_EQ(glb.json["accessors"][index]["componentType"], 5126);
  const auto [at, count] = accessor_span(glb, index, 4);
  std::vector<float> out(count);
  for (std::size_t i = 0; i < count; ++i) out[i] = f32_at(glb.bin, at + 4 * i);
  return out;
}

std::vector<std::uint32_t> uint_accessor(const Glb& glb, std::size_t index) {
  EXPECT_EQ(glb.json["accessors"][index]["componentType"], 5125);
  const auto [at, count] = accessor_span(glb, index, 4);
  std::vector<std::uint32_t> out(count);
  for (std::size_t i = 0; i < count; ++i) out[i] = u32_at(glb.bin, at + 4 * i);
  return out;
}

const Json& primitive(const Glb& glb) { return glb.json["meshes"][0]["primitives"][0]; }

// Bytes of a buffer view (checked to lie in the buffer and start on 8 bytes).
std::string view_bytes(const Glb& glb, std::size_t view_index) {
  const Json& view = glb.json["bufferViews"][view_index];
  const std::size_t at = view["byteOffset"], length = view["byteLength"];
  EXPECT_EQ(at % 8, 0u);
  EXPECT_LE(at + length, glb.bin.size());
  return glb.bin.substr(at, length);
}

// The property table read back: column name → values as JSON (strings, numbers, booleans).
std::map<std::string, Json> property_table(const Glb& glb) {
  const Json& metadata = glb.json["extensions"]["EXT_structural_metadata"];
  const Json& table = metadata["propertyTables"][0];
  const Json& properties =
      metadata["schema"]["classes"][table["class"].get<std::string>()]["properties"];
  const std::size_t count = table["count"];
  std::map<std::string, Json> out;
  for (const auto& [name, entry] : table["properties"].items()) {
    const Json& definition = properties[name];
    const std::string values = view_bytes(glb, entry["values"]);
    Json column = Json::array();
    if (definition["type"] == "STRING") {
      EXPECT_EQ(entry["stringOffsetType"], "UINT32");
      const std::string offsets = view_bytes(glb, entry["stringOffsets"]);
      EXPECT_EQ(offsets.size(), 4 * (count + 1));
      EXPECT_EQ(u32_at(offsets, 0), 0u);
      for (std::size_t i = 0; i < count; ++i) {
        const std::uint32_t a = u32_at(offsets, 4 * i), b = u32_at(offsets, 4 * i + 4);
        EXPECT_LE(a, b);
        EXPECT_LE(b, values.size());
        column.push_back(values.substr(a, b - a));
      }
    } else if (definition["type"] == "BOOLEAN") {
      EXPECT_EQ(values.size(), (count + 7) / 8);
      for (std::size_t i = 0; i < count; ++i)
        column.push_back(((static_cast<unsigned char>(values[i / 8]) >> (i % 8)) & 1) != 0);
    } else if (definition["componentType"] == "FLOAT64") {
      EXPECT_EQ(values.size(), 8 * count);
      for (std::size_t i = 0; i < count; ++i) column.push_back(f64_at(values, 8 * i));
    } else {
      EXPECT_EQ(definition["componentType"], "UINT32");
      EXPECT_EQ(values.size(), 4 * count);
      for (std::size_t i = 0; i < count; ++i) column.push_back(u32_at(values, 4 * i));
    }
    out[name] = std::move(column);
  }
  return out;
}

// ENU (z up) of a stored glTF (y up) position.
Vec3 enu_of(const std::array<float, 3>& p) { return Vec3(p[0], -static_cast<double>(p[2]), p[1]); }

class TileContentTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    auto content = tile_content(sample_objects());
    ASSERT_TRUE(content.ok()) << content.error().message;
    content_ = new TileContent(std::move(content).value());
    glb_ = new Glb(parse_glb(content_->glb));
  }
  static void TearDownTestSuite() {
    delete content_;
    delete glb_;
  }
  static TileContent* content_;
  static Glb* glb_;
};
TileContent* TileContentTest::content_ = nullptr;
Glb* TileContentTest::glb_ = nullptr;

// ---- structure -------------------------------------------------------------------------------

TEST_F(TileContentTest, JsonDescribesOneTrianglePrimitiveWithFeatureIdsAndMetadata) {
  const Json& j = glb_->json;
  EXPECT_EQ(j["asset"]["version"], "2.0");
  EXPECT_EQ(j["extensionsUsed"], Json::array({"EXT_mesh_features", "EXT_structural_metadata"}));
  EXPECT_EQ(j["scenes"][j["scene"].get<std::size_t>()]["nodes"], Json::array({0}));
  EXPECT_FALSE(j["nodes"][0].contains("matrix"));  // y up is in the vertex data
  ASSERT_EQ(j["meshes"].size(), 1u);
  const Json& p = primitive(*glb_);
  EXPECT_EQ(p["mode"], 4);
  EXPECT_EQ(p["attributes"].size(), 3u);
  const Json& ids = p["extensions"]["EXT_mesh_features"]["featureIds"];
  ASSERT_EQ(ids.size(), 1u);
  EXPECT_EQ(ids[0]["featureCount"], sample_objects().size());
  EXPECT_EQ(ids[0]["attribute"], 0);
  EXPECT_EQ(ids[0]["propertyTable"], 0);
  // One buffer: the BIN chunk; every view inside it, 8-byte aligned.
  ASSERT_EQ(j["buffers"].size(), 1u);
  EXPECT_FALSE(j["buffers"][0].contains("uri"));
  EXPECT_EQ(j["buffers"][0]["byteLength"], glb_->bin.size());
  for (std::size_t v = 0; v < j["bufferViews"].size(); ++v) view_bytes(*glb_, v);
}

TEST_F(TileContentTest, AccessorsAgreeWithTheBuffer) {
  const Json& attributes = primitive(*glb_)["attributes"];
  const auto positions = vec3_accessor(*glb_, attributes["POSITION"]);
  const auto normals = vec3_accessor(*glb_, attributes["NORMAL"]);
  const auto features = float_accessor(*glb_, attributes["_FEATURE_ID_0"]);
  const auto indices = uint_accessor(*glb_, primitive(*glb_)["indices"]);
  ASSERT_FALSE(positions.empty());
  EXPECT_EQ(normals.size(), positions.size());
  EXPECT_EQ(features.size(), positions.size());
  EXPECT_EQ(positions.size(), content_->vertices);
  EXPECT_EQ(indices.size(), 3 * content_->triangles);
  const Json& index_accessor = glb_->json["accessors"][primitive(*glb_)["indices"].get<int>()];
  EXPECT_EQ(glb_->json["bufferViews"][index_accessor["bufferView"].get<int>()]["target"], 34963);
  // min/max are exactly the stored extremes.
  const Json& accessor = glb_->json["accessors"][attributes["POSITION"].get<std::size_t>()];
  for (int k = 0; k < 3; ++k) {
    float low = positions[0][k], high = positions[0][k];
    for (const auto& p : positions) {
      low = std::min(low, p[k]);
      high = std::max(high, p[k]);
    }
    EXPECT_EQ(accessor["min"][k].get<double>(), static_cast<double>(low));
    EXPECT_EQ(accessor["max"][k].get<double>(), static_cast<double>(high));
  }
  for (const auto& n : normals) {
    EXPECT_NEAR(std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]), 1.0, 1e-6);
  }
  for (float f : features) {
    EXPECT_EQ(f, std::floor(f));
    EXPECT_GE(f, 0.0f);
    EXPECT_LT(f, static_cast<float>(sample_objects().size()));
  }
  for (std::uint32_t i : indices) EXPECT_LT(i, positions.size());
  // A triangle never mixes features.
  for (std::size_t t = 0; t < indices.size(); t += 3) {
    EXPECT_EQ(features[indices[t]], features[indices[t + 1]]);
    EXPECT_EQ(features[indices[t]], features[indices[t + 2]]);
  }
}

TEST_F(TileContentTest, PropertyTableHasOneRowPerObjectInOrder) {
  const auto table = property_table(*glb_);
  const Json& schema = glb_->json["extensions"]["EXT_structural_metadata"]["schema"];
  EXPECT_EQ(schema["classes"]["object"]["properties"]["id"]["type"], "STRING");
  EXPECT_EQ(schema["classes"]["object"]["properties"]["volume"]["componentType"], "FLOAT64");
  EXPECT_EQ(schema["classes"]["object"]["properties"]["primitive_count"]["componentType"],
            "UINT32");
  EXPECT_EQ(schema["classes"]["object"]["properties"]["valid"]["type"], "BOOLEAN");
  const auto& objects = sample_objects();
  ASSERT_EQ(table.at("id").size(), objects.size());
  for (std::size_t i = 0; i < objects.size(); ++i) {
    const kernel::Shape& shape = objects[i].model.shape;
    const kernel::MassProperties mp = kernel::mass_properties(shape);
    EXPECT_EQ(table.at("id")[i], objects[i].id);
    EXPECT_EQ(content_->object_ids[i], objects[i].id);
    EXPECT_EQ(table.at("cell")[i], "0");
    EXPECT_EQ(table.at("volume")[i].get<double>(), mp.volume);
    EXPECT_EQ(table.at("area")[i].get<double>(), mp.area);
    EXPECT_EQ(table.at("primitive_count")[i], objects[i].primitives.size());
    EXPECT_EQ(table.at("valid")[i], kernel::check_shape(shape).valid());
  }
  EXPECT_EQ(table.at("primitive_types")[2], "box,cylinder");
  EXPECT_EQ(table.at("primitive_types")[1], "cylinder");
}

// ---- geometry --------------------------------------------------------------------------------

// Per feature: the triangles welded by position are closed, and enclose the object's volume
// (positive: outward, and the y-up rotation is proper) within the chordal error.
TEST_F(TileContentTest, EachObjectIsClosedOutwardAndHasItsVolume) {
  const Json& attributes = primitive(*glb_)["attributes"];
  const auto positions = vec3_accessor(*glb_, attributes["POSITION"]);
  const auto features = float_accessor(*glb_, attributes["_FEATURE_ID_0"]);
  const auto indices = uint_accessor(*glb_, primitive(*glb_)["indices"]);
  const auto& objects = sample_objects();
  std::vector<double> volumes(objects.size(), 0.0);
  std::vector<std::map<std::pair<std::array<float, 3>, std::array<float, 3>>, int>> edges(
      objects.size());
  for (std::size_t t = 0; t < indices.size(); t += 3) {
    const auto f = static_cast<std::size_t>(features[indices[t]]);
    const Vec3 a = enu_of(positions[indices[t]]), b = enu_of(positions[indices[t + 1]]),
               c = enu_of(positions[indices[t + 2]]);
    volumes[f] += a.dot(b.cross(c)) / 6.0;
    for (int k = 0; k < 3; ++k)
      ++edges[f][{positions[indices[t + k]], positions[indices[t + (k + 1) % 3]]}];
  }
  for (std::size_t f = 0; f < objects.size(); ++f) {
    const double exact = kernel::mass_properties(objects[f].model.shape).volume;
    EXPECT_GT(volumes[f], 0.0) << objects[f].id;
    EXPECT_NEAR(volumes[f], exact, 0.02 * exact) << objects[f].id;
    for (const auto& [edge, n] : edges[f]) {
      EXPECT_EQ(n, 1) << objects[f].id;
      const auto back = edges[f].find({edge.second, edge.first});
      EXPECT_TRUE(back != edges[f].end() && back->second == 1) << objects[f].id;
    }
  }
}

TEST_F(TileContentTest, GltfIsYUpAndFlatFacesHaveFlatNormals) {
  const Json& attributes = primitive(*glb_)["attributes"];
  const auto positions = vec3_accessor(*glb_, attributes["POSITION"]);
  const auto normals = vec3_accessor(*glb_, attributes["NORMAL"]);
  const auto features = float_accessor(*glb_, attributes["_FEATURE_ID_0"]);
  // The block (feature 0) spans x 0..2, y 0..3, z 0..4 in ENU: glTF x 0..2, y 0..4, z −3..0.
  std::size_t block_vertices = 0;
  std::set<std::array<float, 3>> block_normals;
  for (std::size_t i = 0; i < positions.size(); ++i) {
    if (features[i] != 0.0f) continue;
    ++block_vertices;
    EXPECT_GE(positions[i][1], 0.0f);
    EXPECT_LE(positions[i][1], 4.0f);
    EXPECT_GE(positions[i][2], -3.0f);
    EXPECT_LE(positions[i][2], 0.0f);
    block_normals.insert(normals[i]);
    // The normal points out of the face the vertex is on: up for the top (glTF +y).
    if (positions[i][1] == 4.0f && normals[i][1] > 0.5f) {
      EXPECT_EQ(normals[i], (std::array<float, 3>{0, 1, 0}));
    }
  }
  // Six faces of four corners each, each corner with its face's normal.
  EXPECT_EQ(block_vertices, 24u);
  const std::set<std::array<float, 3>> axes = {{1, 0, 0},  {-1, 0, 0}, {0, 1, 0},
                                               {0, -1, 0}, {0, 0, 1},  {0, 0, -1}};
  EXPECT_EQ(block_normals, axes);
  // The ENU bounds of the content, back in z up: from the block's corner to the tower's top.
  EXPECT_EQ(content_->low.x(), 0.0);
  EXPECT_EQ(content_->low.z(), 0.0);
  EXPECT_NEAR(content_->high.z(), 6.0, 1e-6);
}

// ---- determinism and errors ------------------------------------------------------------------

TEST_F(TileContentTest, SameObjectsGiveTheSameBytes) {
  auto again = tile_content(build_objects());
  ASSERT_TRUE(again.ok());
  EXPECT_EQ(again.value().glb, content_->glb);
}

// What the tileset job tells apart: content with no object to show (GeometryInvalid: the job
// publishes no tileset and says why) from a bad call (InputInvalid).
TEST(TileContent, NothingToShowAndBadCallsAreDifferentErrors) {
  const IndexObject block = object("b", leaf(box({0, 0, 0}, {1, 1, 1}), "b"));
  TileContentOptions outside;
  outside.to_enu = [](const Vec3&) { return Vec3(std::nan(""), 0.0, 0.0); };
  auto nothing = tile_content({block}, outside);
  ASSERT_FALSE(nothing.ok());
  EXPECT_EQ(nothing.error().code, ErrorCode::GeometryInvalid);
  EXPECT_NE(nothing.error().message.find("no object has triangles"), std::string::npos);
  EXPECT_NE(nothing.error().message.find("outside the CRS's domain"), std::string::npos);

  auto twice = tile_content({block, block});
  ASSERT_FALSE(twice.ok());
  EXPECT_EQ(twice.error().code, ErrorCode::InputInvalid);
  TileContentOptions no_tolerance;
  no_tolerance.chordal_tolerance = 0.0;
  EXPECT_EQ(tile_content({block}, no_tolerance).error().code, ErrorCode::InputInvalid);
}

TEST(GltfWriter, BadInputsAreNamedErrors) {
  GltfMesh mesh;
  mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  mesh.normals = {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}};
  mesh.feature_ids = {0, 0, 0};
  mesh.indices = {0, 1, 2};
  PropertyTable table;
  table.count = 1;
  table.columns = {{"id", "", std::vector<std::string>{"a"}}};
  ASSERT_TRUE(glb_bytes(mesh, table).ok());
  auto expect_error = [&](const GltfMesh& m, const PropertyTable& t, const std::string& what) {
    auto r = glb_bytes(m, t);
    ASSERT_FALSE(r.ok()) << what;
    EXPECT_EQ(r.error().code, ErrorCode::InputInvalid);
    EXPECT_NE(r.error().message.find(what), std::string::npos) << r.error().message;
  };
  GltfMesh m = mesh;
  m.indices[2] = 3;
  expect_error(m, table, "index 3 out of range");
  m = mesh;
  m.feature_ids[1] = 1;
  expect_error(m, table, "feature id 1 out of range");
  m = mesh;
  m.normals.pop_back();
  expect_error(m, table, "differ in number");
  m = mesh;
  m.positions[0][0] = NAN;
  expect_error(m, table, "not finite");
  PropertyTable t = table;
  t.columns.push_back({"volume", "", std::vector<double>{1.0, 2.0}});
  expect_error(mesh, t, "\"volume\" has 2 values for 1 rows");
  t = table;
  t.columns[0].name = "bad name";
  expect_error(mesh, t, "not an identifier");
  expect_error(GltfMesh{}, table, "no triangles");
}

TEST(GltfWriter, EmptyStringsAndBooleansPackAsTheSpecSays) {
  GltfMesh mesh;
  mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  mesh.normals = {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}};
  mesh.feature_ids = {0, 0, 8};
  mesh.indices = {0, 1, 2};
  PropertyTable table;
  table.count = 9;
  std::vector<bool> flags(9, false);
  flags[0] = flags[3] = flags[8] = true;
  table.columns = {{"empty", "", std::vector<std::string>(9, "")}, {"flag", "", flags}};
  auto bytes = glb_bytes(mesh, table);
  ASSERT_TRUE(bytes.ok()) << bytes.error().message;
  const Glb glb = parse_glb(bytes.value());
  const auto columns = property_table(glb);
  EXPECT_EQ(columns.at("empty"), Json(std::vector<std::string>(9, "")));
  EXPECT_EQ(columns.at("flag"), Json(flags));
  const Json& properties =
      glb.json["extensions"]["EXT_structural_metadata"]["propertyTables"][0]["properties"];
  auto view_length = [&](const std::string& name) {
    return glb.json["bufferViews"][properties[name]["values"].get<std::size_t>()]["byteLength"];
  };
  EXPECT_EQ(view_length("flag"), 2);  // 9 bits
  // glTF has no empty views: all-empty strings keep one byte that no offset reaches.
  EXPECT_EQ(view_length("empty"), 1);
}

// ---- placement -------------------------------------------------------------------------------

// `cmd` with `input` on stdin; stdout, or nullopt when it fails.
std::optional<std::string> run_with_input(const std::string& cmd, const std::string& input) {
  test::TempDir dir("csgtile-tiles-cmd-");
  std::ofstream(dir / "in") << input;
  const std::string line =
      cmd + " < '" + (dir / "in").string() + "' > '" + (dir / "out").string() + "' 2>/dev/null";
  if (std::system(line.c_str()) != 0) return std::nullopt;
  return test::read_file(dir / "out");
}

bool cs2cs_available() { return std::system("command -v cs2cs >/dev/null 2>&1") == 0; }

std::optional<Vec3> cs2cs_point(const std::string& from, const std::string& to, const Vec3& p) {
  std::ostringstream in;
  in.precision(17);
  in << p.x() << ' ' << p.y() << ' ' << p.z() << '\n';
  const auto out = run_with_input("cs2cs -f %.10f " + from + " " + to, in.str());
  if (!out) return std::nullopt;
  std::istringstream fields(*out);
  Vec3 v;
  if (!(fields >> v.x() >> v.y() >> v.z())) return std::nullopt;
  return v;
}

geo::Crs crs(const std::string& text) {
  auto c = geo::crs_from_config(text);
  EXPECT_TRUE(c.ok()) << text;
  return c.value();
}

Eigen::Matrix4d matrix_of(const std::array<double, 16>& column_major) {
  Eigen::Matrix4d m;
  for (int c = 0; c < 4; ++c) {
    for (int r = 0; r < 4; ++r) m(r, c) = column_major[4 * static_cast<std::size_t>(c) + r];
  }
  return m;
}

TEST(TilePlacement, TransformHasOrthonormalEnuAxesAndTheOriginsEcef) {
  for (const auto& [text, origin] :
       {std::pair{std::string("EPSG:32631"), Vec3(640000, 5700000, 10)},
        std::pair{std::string("EPSG:28992+5709"), Vec3(155000, 463000, 1.25)}}) {
    auto georef = geo::Georeferencer::create_at(crs(text), origin);
    ASSERT_TRUE(georef.ok());
    const Eigen::Matrix4d m = matrix_of(tile_transform(georef.value().frame()));
    const Eigen::Matrix3d r = m.topLeftCorner<3, 3>();
    EXPECT_NEAR((r.transpose() * r - Eigen::Matrix3d::Identity()).norm(), 0.0, 1e-14) << text;
    EXPECT_NEAR(r.determinant(), 1.0, 1e-14) << text;
    EXPECT_EQ(m.row(3), Eigen::RowVector4d(0, 0, 0, 1));
    // East is horizontal (no z), up is the outward ellipsoid normal: along the radius,
    // within the ellipsoid's deflection (< 0.2°).
    EXPECT_EQ(r(2, 0), 0.0);
    const Vec3 t = m.col(3).head<3>();
    EXPECT_GT(r.col(2).dot(t.normalized()), std::cos(0.2 * std::numbers::pi / 180)) << text;
  }
}

// The origin maps to the ECEF PROJ computes for the scene origin, and the axes are those of
// the geodetic position PROJ gives (UTM on WGS 84: no datum shift, agreement to 1 mm).
TEST(TilePlacement, OriginAndAxesAgreeWithCs2cs) {
  if (!cs2cs_available()) {
    GTEST_SKIP() << "PROJ's cs2cs not installed (apt-get install proj-bin): oracle test skipped";
  }
  const Vec3 origin(640000, 5700000, 10);
  auto georef = geo::Georeferencer::create_at(crs("EPSG:32631"), origin);
  ASSERT_TRUE(georef.ok());
  const Eigen::Matrix4d m = matrix_of(tile_transform(georef.value().frame()));
  const auto ecef = cs2cs_point("EPSG:32631", "EPSG:4978", origin);
  ASSERT_TRUE(ecef.has_value());
  EXPECT_LT((m.col(3).head<3>() - *ecef).norm(), 1e-3);
  const auto geodetic = cs2cs_point("EPSG:32631", "EPSG:4979", origin);  // lat, lon, h
  ASSERT_TRUE(geodetic.has_value());
  const double phi = geodetic->x() * std::numbers::pi / 180;
  const double lambda = geodetic->y() * std::numbers::pi / 180;
  const Vec3 east(-std::sin(lambda), std::cos(lambda), 0);
  const Vec3 north(-std::sin(phi) * std::cos(lambda), -std::sin(phi) * std::sin(lambda),
                   std::cos(phi));
  const Vec3 up(std::cos(phi) * std::cos(lambda), std::cos(phi) * std::sin(lambda), std::sin(phi));
  EXPECT_LT((m.col(0).head<3>() - east).norm(), 1e-9);
  EXPECT_LT((m.col(1).head<3>() - north).norm(), 1e-9);
  EXPECT_LT((m.col(2).head<3>() - up).norm(), 1e-9);

  // RD New: cs2cs takes EPSG:4833 to WGS 84, we EPSG:9281 (geo/georeference.h): the
  // Helmert sets differ by less than 1 m horizontally. Heights are not compared: we take
  // z as a height on the datum's Bessel ellipsoid (≈ 43 m below WGS 84's here, about the
  // geoid's height, so NAP heights land near the truth), cs2cs passes a 2D CRS's z through as
  // a WGS 84 height.
  const Vec3 rd(155000, 463000, 1.25);
  auto rd_georef = geo::Georeferencer::create_at(crs("EPSG:28992+5709"), rd);
  ASSERT_TRUE(rd_georef.ok());
  const auto rd_geodetic = cs2cs_point("EPSG:28992", "EPSG:4326", rd);  // lat, lon, h
  ASSERT_TRUE(rd_geodetic.has_value());
  const Vec3 ours = matrix_of(tile_transform(rd_georef.value().frame())).col(3).head<3>();
  const geo::GeodeticPoint g = geo::ecef_to_geodetic(geo::Ellipsoid{}, ours);
  const double gap_m = 6.37e6 * std::numbers::pi / 180 *
                       std::hypot(g.latitude_deg - rd_geodetic->x(),
                                  (g.longitude_deg - rd_geodetic->y()) *
                                      std::cos(g.latitude_deg * std::numbers::pi / 180));
  std::cout << "[agreement] RD tile origin vs cs2cs EPSG:28992 -> EPSG:4326: " << gap_m
            << " m horizontally, height " << g.height_m << " m on WGS 84 for NAP 1.25 m\n";
  EXPECT_LT(gap_m, 1.0);
}

// Points all over a box (its faces sampled densely, through the frame's exact ENU → ECEF →
// geodetic) fall inside its region, and the region is not much larger.
TEST(TilePlacement, RegionHoldsItsBox) {
  struct Case {
    std::string crs;
    Vec3 origin, low, high;
  };
  const Case cases[] = {
      {"EPSG:28992+5709", {155000, 463000, 1.25}, {-3, -2, 0}, {40, 25, 18}},
      {"EPSG:28992+5709", {155000, 463000, 0}, {-1500, -400, -5}, {1800, 2200, 300}},
      {"EPSG:32631", {640000, 5700000, 10}, {0, 0, 0}, {5000, 5000, 100}},
      {"EPSG:3031", {-1000000, 500000, 0}, {-300, -300, 0}, {300, 300, 50}},
  };
  const geo::Ellipsoid wgs84;
  for (const Case& c : cases) {
    auto georef = geo::Georeferencer::create_at(crs(c.crs), c.origin);
    ASSERT_TRUE(georef.ok());
    const Region region = enu_box_region(georef.value(), c.low, c.high);
    const Eigen::Matrix4d m = matrix_of(tile_transform(georef.value().frame()));
    double lowest = INFINITY, highest = -INFINITY;
    constexpr int kSteps = 24;
    for (int i = 0; i <= kSteps; ++i) {
      for (int j = 0; j <= kSteps; ++j) {
        for (int k = 0; k <= kSteps; ++k) {
          const Vec3 f = Vec3(i, j, k) / kSteps;
          const Vec3 p = c.low + (c.high - c.low).cwiseProduct(f);
          const Vec3 ecef = (m * p.homogeneous()).head<3>();
          const geo::GeodeticPoint g = geo::ecef_to_geodetic(wgs84, ecef);
          const double lon = g.longitude_deg * std::numbers::pi / 180;
          const double lat = g.latitude_deg * std::numbers::pi / 180;
          EXPECT_GE(lon, region[0]) << c.crs;
          EXPECT_LE(lon, region[2]) << c.crs;
          EXPECT_GE(lat, region[1]) << c.crs;
          EXPECT_LE(lat, region[3]) << c.crs;
          EXPECT_GE(g.height_m, region[4]) << c.crs;
          EXPECT_LE(g.height_m, region[5]) << c.crs;
          lowest = std::min(lowest, g.height_m);
          highest = std::max(highest, g.height_m);
        }
      }
    }
    // Tight: heights within the margin (1 cm plus the curvature term, < 2 m at 5 km).
    const double span = std::hypot(c.high.x() - c.low.x(), c.high.y() - c.low.y());
    EXPECT_LT(lowest - region[4], 0.011 + 3.0 * span * span / 6.3e6) << c.crs;
    EXPECT_LT(region[5] - highest, 0.011 + 3.0 * span * span / 6.3e6) << c.crs;
  }
}

TEST(Tileset, JsonHasVersionRegionTransformAndContent) {
  const Region region = {0.1, 0.9, 0.2, 1.0, -5, 50};
  std::array<double, 16> transform{};
  for (std::size_t i = 0; i < 4; ++i) transform[5 * i] = 1.0;
  TilesetOptions options;
  options.geometric_error = 30;
  options.tile_geometric_error = 0.01;
  const std::string text = tileset_json(region, transform, options);
  EXPECT_EQ(text.back(), '\n');
  const Json t = Json::parse(text);
  EXPECT_EQ(t["asset"]["version"], "1.1");
  EXPECT_EQ(t["geometricError"], 30.0);
  EXPECT_EQ(t["root"]["boundingVolume"]["region"], Json(region));
  EXPECT_EQ(t["root"]["transform"], Json(transform));
  EXPECT_EQ(t["root"]["geometricError"], 0.01);
  EXPECT_EQ(t["root"]["refine"], "ADD");
  EXPECT_EQ(t["root"]["content"]["uri"], "model.glb");
}

// ---- the Khronos glTF validator --------------------------------------------------------------

using test::CommandResult;
using test::quoted;
CommandResult run_command(const std::string& command) { return test::run_command(command, true); }

// npm's gltf-validator package: $CSGTILE_GLTF_VALIDATOR_DIR, else the build directory's npm
// install (deploy/run-tests.sh: `npm install --prefix build/npm gltf-validator@2.0.0-dev.3.10`).
fs::path validator_dir() {
  if (const char* env = std::getenv("CSGTILE_GLTF_VALIDATOR_DIR"); env != nullptr && *env != '\0')
    return env;
  return CSGTILE_GLTF_VALIDATOR_DIR;
}

// Without node or the validator the checks skip, unless CSGTILE_REQUIRE_GLTF_VALIDATOR=1
// makes their absence a failure (CI).
#define REQUIRE_GLTF_VALIDATOR()                                                      \
  do {                                                                                \
    std::string why_;                                                                 \
    if (std::system("command -v node >/dev/null 2>&1") != 0) {                        \
      why_ = "node not found (apt-get install nodejs)";                               \
    } else if (!fs::exists(validator_dir() / "package.json")) {                       \
      why_ = "gltf-validator not found in " + validator_dir().string() +              \
             " (set CSGTILE_GLTF_VALIDATOR_DIR, or npm install --prefix <build>/npm " \
             "gltf-validator as deploy/run-tests.sh does)";                           \
    }                                                                                 \
    if (!why_.empty()) {                                                              \
      const char* require_ = std::getenv("CSGTILE_REQUIRE_GLTF_VALIDATOR");           \
      if (require_ != nullptr && std::string(require_) == "1") FAIL() << why_;        \
      GTEST_SKIP() << why_;                                                           \
    }                                                                                 \
  } while (false)

// The validator's counts and messages for `bytes` (tests/support/validate_gltf.cjs).
Json validate(const std::string& bytes, const fs::path& dir) {
  const fs::path file = dir / "model.glb";
  std::ofstream(file, std::ios::binary) << bytes;
  const CommandResult r =
      run_command("node " + quoted(test::source_dir() / "tests/support/validate_gltf.cjs") + " " +
                  quoted(validator_dir()) + " " + quoted(file));
  EXPECT_EQ(r.exit_code, 0) << r.out;
  const Json report = Json::parse(r.out, nullptr, false);
  EXPECT_FALSE(report.is_discarded()) << r.out;
  return report.is_discarded() ? Json::object() : report;
}

void print_issues(const Json& report, const std::string& what) {
  std::cout << "[gltf-validator] " << what << ": " << report.value("numErrors", -1) << " errors, "
            << report.value("numWarnings", -1) << " warnings, " << report.value("numInfos", -1)
            << " infos\n";
  for (const Json& m : report.value("messages", Json::array())) {
    const std::string text = m.get<std::string>();
    if (text.rfind("info", 0) != 0 && text.rfind("hint", 0) != 0) std::cout << "  " << text << "\n";
  }
}

TEST_F(TileContentTest, KhronosValidatorFindsNoErrors) {
  REQUIRE_GLTF_VALIDATOR();
  test::TempDir dir("csgtile-tiles-validator-");
  const Json report = validate(content_->glb, dir.path());
  print_issues(report, "sample objects");
  EXPECT_EQ(report.value("numErrors", -1), 0) << report.dump(2);
}

TEST(GltfValidator, IsLiveAndReportsAWrongMinimum) {
  REQUIRE_GLTF_VALIDATOR();
  test::TempDir dir("csgtile-tiles-validator-bad-");
  auto content = tile_content({object("b", leaf(box({1, 2, 3}, {1, 1, 1}), "b"))});
  ASSERT_TRUE(content.ok());
  // "min":[1.0,3.0,-3.0] (y up) becomes [1.0,4.0,-3.0]: the stored positions disagree.
  std::string bytes = content.value().glb;
  const std::size_t at = bytes.find("\"min\":[1.0,3.0,");
  ASSERT_NE(at, std::string::npos) << "the minimum is not where the test expects it";
  bytes[at + 11] = '4';
  const Json report = validate(bytes, dir.path());
  EXPECT_GT(report.value("numErrors", 0), 0) << report.dump(2);
  EXPECT_NE(report.dump().find("ACCESSOR_MIN_MISMATCH"), std::string::npos) << report.dump(2);
}

// ---- the run ---------------------------------------------------------------------------------

// Two one-box scenes and a cylinder scene in RD New + NAP, 100 m apart.
std::vector<std::string> write_rd_scenes(const test::TempDir& dir) {
  auto write_scene = [&](const std::string& name, double x, const std::string& primitive) {
    const fs::path path = dir / (name + ".json");
    std::ofstream(path) << R"({"name":")" << name << R"(","crs":"EPSG:28992+5709","origin":[)" << x
                        << R"(,463000,1.25],"primitives":[)" << primitive << "]}";
    return path.string();
  };
  const std::string cube =
      R"({"type":"box","id":"b","size":[2,2,3],"placement":[[1,0,0,0],[0,1,0,0],[0,0,1,0]]})";
  const std::string tower =
      R"({"type":"cylinder","id":"c","r":1,"h":8,"placement":[[1,0,0,0],[0,1,0,0],[0,0,1,0]]})";
  return {write_scene("west", 155000, cube), write_scene("east", 155100, cube),
          write_scene("north", 155050, tower)};
}

TEST(TilesRun, RunPublishesTheTilesetAndContentAndNamesThemInTheManifest) {
  test::TempDir dir("csgtile-run-tiles-");
  config::Config c;
  c.run.name = "rd";
  c.run.output = (dir / "out").string();
  c.run.inputs = write_rd_scenes(dir);
  Logger log(config::LogLevel::Error, config::LogFormat::Json, stderr);
  RunSummary summary;
  ASSERT_TRUE(run_embedded(c, log, summary).ok());
  const auto manifest = Json::parse(test::read_file(summary.manifest));
  const Json& tiles = manifest["tiles"];
  ASSERT_TRUE(tiles.is_object()) << manifest.dump(2);
  const std::string text = test::read_file(summary.run_dir / "tiles/tileset.json");
  const std::string glb_bytes_on_disk = test::read_file(summary.run_dir / "tiles/model.glb");
  EXPECT_EQ(tiles["key"], "tiles/tileset.json");
  EXPECT_EQ(tiles["sha256"], sha256_hex(text));
  EXPECT_EQ(tiles["bytes"], text.size());
  EXPECT_EQ(tiles["content"], "tiles/model.glb");
  EXPECT_EQ(tiles["content_sha256"], sha256_hex(glb_bytes_on_disk));
  EXPECT_EQ(tiles["content_bytes"], glb_bytes_on_disk.size());
  EXPECT_EQ(tiles["objects"], manifest["index"]["objects"]);
  EXPECT_FALSE(manifest.contains("tiles_skipped"));

  // The features are the index's objects, in its order.
  const Glb glb = parse_glb(glb_bytes_on_disk);
  const auto table = property_table(glb);
  auto index = TopologyIndexReader::open(summary.run_dir / "index.gpkg");
  ASSERT_TRUE(index.ok());
  const auto ids = index.value()->sql("SELECT object_id FROM objects ORDER BY fid");
  ASSERT_TRUE(ids.ok());
  ASSERT_EQ(table.at("id").size(), ids->size());
  for (std::size_t i = 0; i < ids->size(); ++i) EXPECT_EQ(table.at("id")[i], (*ids)[i][0]);

  // Every vertex, placed by the transform, lies in the region; the east box is 100 m east
  // of the west one in ENU too (up to the grid's scale and convergence: < 2 cm here).
  const Json t = Json::parse(text);
  std::array<double, 16> transform{};
  for (std::size_t i = 0; i < 16; ++i) transform[i] = t["root"]["transform"][i];
  const Eigen::Matrix4d m = matrix_of(transform);
  const Json& region = t["root"]["boundingVolume"]["region"];
  const auto positions = vec3_accessor(glb, primitive(glb)["attributes"]["POSITION"]);
  const auto features = float_accessor(glb, primitive(glb)["attributes"]["_FEATURE_ID_0"]);
  std::vector<Vec3> lowest(3, Vec3::Constant(INFINITY));
  for (std::size_t i = 0; i < positions.size(); ++i) {
    const Vec3 enu = enu_of(positions[i]);
    const auto f = static_cast<std::size_t>(features[i]);
    lowest[f] = lowest[f].cwiseMin(enu);
    const geo::GeodeticPoint g =
        geo::ecef_to_geodetic(geo::Ellipsoid{}, (m * enu.homogeneous()).head<3>());
    const double lon = g.longitude_deg * std::numbers::pi / 180;
    const double lat = g.latitude_deg * std::numbers::pi / 180;
    EXPECT_TRUE(lon >= region[0] && lon <= region[2] && lat >= region[1] && lat <= region[3] &&
                g.height_m >= region[4] && g.height_m <= region[5])
        << "vertex " << i;
  }
  EXPECT_NEAR(lowest[0].x(), 0.0, 1e-3);
  EXPECT_NEAR(lowest[1].x() - lowest[0].x(), 100.0, 0.02);
  EXPECT_NEAR(lowest[1].y() - lowest[0].y(), 0.0, 0.02);
  EXPECT_EQ(t["root"]["geometricError"], c.kernel.chordal_tolerance);

  // A second run writes the same bytes.
  RunSummary again;
  ASSERT_TRUE(run_embedded(c, log, again).ok());
  EXPECT_EQ(test::read_file(again.run_dir / "tiles/model.glb"), glb_bytes_on_disk);
  EXPECT_EQ(test::read_file(again.run_dir / "tiles/tileset.json"), text);
}

TEST(TilesRun, RunOutputPassesTheKhronosValidator) {
  REQUIRE_GLTF_VALIDATOR();
  test::TempDir dir("csgtile-run-tiles-validator-");
  config::Config c;
  c.run.name = "rd";
  c.run.output = (dir / "out").string();
  c.run.inputs = write_rd_scenes(dir);
  Logger log(config::LogLevel::Error, config::LogFormat::Json, stderr);
  RunSummary summary;
  ASSERT_TRUE(run_embedded(c, log, summary).ok());
  const Json report = validate(test::read_file(summary.run_dir / "tiles/model.glb"), dir.path());
  print_issues(report, "run output");
  EXPECT_EQ(report.value("numErrors", -1), 0) << report.dump(2);
}

TEST(TilesRun, RunWithoutACrsWritesNoTilesAndSaysWhy) {
  test::TempDir dir("csgtile-run-tiles-nocrs-");
  config::Config c;
  c.run.name = "t";
  c.run.output = (dir / "out").string();
  c.run.inputs = {(test::source_dir() / "config/examples/scenes/pavilion.json").string()};
  // Tiles left by an earlier run in the same directory go.
  ASSERT_TRUE(write_file_atomic(fs::path(c.run.output) / "runs/t/tiles/model.glb", "stale").ok());
  Logger log(config::LogLevel::Error, config::LogFormat::Json, stderr);
  RunSummary summary;
  ASSERT_TRUE(run_embedded(c, log, summary).ok());
  const auto manifest = Json::parse(test::read_file(summary.manifest));
  EXPECT_TRUE(manifest["tiles"].is_null());
  EXPECT_NE(manifest["tiles_skipped"].get<std::string>().find("georeference"), std::string::npos);
  EXPECT_FALSE(fs::exists(summary.run_dir / "tiles/model.glb"));
  EXPECT_FALSE(fs::exists(summary.run_dir / "tiles/tileset.json"));
}

}  // namespace
}  // namespace csgtile::worker
