// Buildings at two levels of detail (issue #18 items 5 and 6): in CityJSON the model as LoD2.2,
// its block (the footprint up to the roof's 70th percentile) as LoD1.2, the heights; a
// building whose model did not fuse keeps its block with the reason. In the GeoPackage the
// blocks' layer (lod12) and the LoD and heights of every object, valid for GDAL.

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <sstream>

#include "city/block_records.h"
#include "csgtile/geo/crs.h"
#include "csgtile/kernel/explorer.h"
#include "csgtile/kernel/mass_properties.h"
#include "csgtile/kernel/native_format.h"
#include "csgtile/kernel/tessellation.h"
#include "export/cityjson_seq.h"
#include "export/tile_content.h"
#include "export/topology_index.h"
#include "index_object_builder.h"
#include "model_builders.h"
#include "test_commands.h"
#include "test_support.h"

namespace csgtile::worker {
namespace {

using Json = nlohmann::json;
using kernel::Vec2;
using kernel::Vec3;

using test::leaf;
using test::rectangle;

kernel::PrimitiveSpec part(std::vector<Vec2> profile, double base, double height) {
  return test::extrusion_at(std::move(profile), base, height);
}

kernel::CsgModel gable_house() { return leaf(test::gable_house(), "house"); }

std::vector<Json> features_of(const std::vector<IndexObject>& objects,
                              const CityJsonOptions& options, CityJsonStats& stats) {
  auto text = cityjson_seq(objects, options, &stats);
  EXPECT_TRUE(text.ok()) << text.error().message;
  std::vector<Json> out;
  std::istringstream in(text.ok() ? text.value() : std::string());
  std::string line;
  std::getline(in, line);  // the header
  while (std::getline(in, line)) out.push_back(Json::parse(line));
  return out;
}

const Json& city_object(const Json& f) { return f["CityObjects"][f["id"].get<std::string>()]; }

// Heights of a geometry's vertices in the file's CRS: lowest and highest.
std::pair<double, double> z_range(const Json& feature, const Json& geometry,
                                  const CityJsonOptions& o) {
  double low = INFINITY, high = -INFINITY;
  std::function<void(const Json&)> walk = [&](const Json& j) {
    if (j.is_number_integer()) {
      const double z =
          feature["vertices"][j.get<std::size_t>()][2].get<double>() * o.scale + o.origin.z();
      low = std::min(low, z);
      high = std::max(high, z);
      return;
    }
    for (const Json& c : j) walk(c);
  };
  walk(geometry["boundaries"]);
  return {low, high};
}

TEST(CityJsonLods, ABuildingHasItsModelAsLod22ItsLevelsAsLod13AndItsBlockAsLod12) {
  std::vector<IndexObject> objects = {test::index_object("house", gable_house())};
  add_building_lods(objects, 0.01, 1e-7);
  CityJsonOptions options;
  options.origin = Vec3(85000, 446000, 1.5);
  CityJsonStats stats;
  const auto features = features_of(objects, options, stats);
  ASSERT_EQ(features.size(), 1u);
  const Json& o = city_object(features[0]);
  EXPECT_EQ(o["type"], "Building");
  ASSERT_EQ(o["geometry"].size(), 3u);
  const Json& lod22 = o["geometry"][0];
  const Json& lod13 = o["geometry"][1];
  const Json& lod12 = o["geometry"][2];
  EXPECT_EQ(lod22["lod"], "2.2");
  EXPECT_EQ(lod22["type"], "Solid");
  // One roof part: its LoD1.3 is the block.
  EXPECT_EQ(lod13["lod"], "1.3");
  EXPECT_EQ(lod13["type"], "Solid");
  EXPECT_EQ(lod13["boundaries"][0].size(), 6u);
  EXPECT_EQ(lod12["lod"], "1.2");
  EXPECT_EQ(lod12["type"], "Solid");
  // The block: a box of six surfaces from the ground to the roof's 70th percentile.
  EXPECT_EQ(lod12["boundaries"][0].size(), 6u);
  const auto [low, high] = z_range(features[0], lod12, options);
  EXPECT_NEAR(low, 1.5, 1e-9);
  EXPECT_NEAR(high, 1.5 + 7.1, 0.001);
  const Json& a = o["attributes"];
  EXPECT_EQ(a["lod_reached"], "2.2");
  EXPECT_NEAR(a["h_ground"].get<double>(), 1.5, 1e-9);
  EXPECT_NEAR(a["h_roof_min"].get<double>(), 6.5, 1e-9);
  EXPECT_NEAR(a["h_roof_50p"].get<double>(), 8.0, 1e-9);
  EXPECT_NEAR(a["h_roof_70p"].get<double>(), 8.6, 1e-9);
  EXPECT_NEAR(a["h_roof_max"].get<double>(), 9.5, 1e-9);
  EXPECT_EQ(a["roof_surfaces"], 2);
  EXPECT_FALSE(a.contains("lod22_failure"));
  EXPECT_FALSE(a.contains("lod12_failure"));
  EXPECT_FALSE(a.contains("lod13_failure"));
  // Semantics of the block: one roof, one ground, four walls.
  std::map<std::string, int> kinds;
  for (const Json& v : lod12["semantics"]["values"][0]) {
    ++kinds[lod12["semantics"]["surfaces"][v.get<std::size_t>()]["type"].get<std::string>()];
  }
  EXPECT_EQ(kinds["RoofSurface"], 1);
  EXPECT_EQ(kinds["GroundSurface"], 1);
  EXPECT_EQ(kinds["WallSurface"], 4);
}

// The parts of a building whose fuse failed: a Building of its blocks alone (CityJSON admits
// no MultiSolid for a Building), the reason recorded; the blocks cover both parts.
TEST(CityJsonLods, ABuildingWhoseModelDidNotFuseKeepsItsBlockWithTheReason) {
  const kernel::CsgModel a = leaf(part(rectangle(0, 0, 10, 6), 0.0, 5.0), "a");
  const kernel::CsgModel b = leaf(part(rectangle(8, 0, 16, 10), 0.0, 9.0), "b");
  kernel::CsgModel unfused;
  auto compound = kernel::ShapeFactory::compound({a.shape, b.shape});
  ASSERT_TRUE(compound.ok());
  unfused.shape = compound.value();
  unfused.nodes = {a.nodes[0], b.nodes[0],
                   kernel::CsgNode{kernel::CsgNodeKind::Fuse, {}, {}, {0, 1}}};
  unfused.face_sources.resize(
      kernel::map_child_shapes(unfused.shape, kernel::ShapeKind::Face).size());
  std::vector<IndexObject> objects = {test::index_object("parts", unfused)};
  objects[0].fuse_error = "unsupported: the Booleans gave up";
  add_building_lods(objects, 0.01, 1e-7);
  ASSERT_TRUE(objects[0].lod12.has_value()) << objects[0].lod12_error;
  CityJsonOptions options;
  CityJsonStats stats;
  const auto features = features_of(objects, options, stats);
  ASSERT_EQ(features.size(), 1u);
  const Json& o = city_object(features[0]);
  EXPECT_EQ(o["type"], "Building");
  // Its parts at their own heights (5 m and 9 m) as LoD1.3, the block as LoD1.2.
  ASSERT_EQ(o["geometry"].size(), 2u);
  EXPECT_EQ(o["geometry"][0]["lod"], "1.3");
  EXPECT_EQ(o["geometry"][0]["type"], "Solid");
  EXPECT_EQ(o["geometry"][1]["lod"], "1.2");
  EXPECT_EQ(o["geometry"][1]["type"], "Solid");
  EXPECT_EQ(o["attributes"]["lod_reached"], "1.3");
  EXPECT_EQ(o["attributes"]["lod22_failure"], "unsupported: the Booleans gave up");
}

// Objects that are not buildings (another primitive among their leaves) keep one lod-2
// geometry and no LoD attributes.
TEST(CityJsonLods, OtherObjectsHaveNoBlock) {
  kernel::PrimitiveSpec column;
  column.type = kernel::PrimitiveType::Cylinder;
  column.radius = 0.3;
  column.height = 4.0;
  std::vector<IndexObject> objects = {test::index_object("column", leaf(column, "c"))};
  add_building_lods(objects, 0.01, 1e-7);
  EXPECT_FALSE(objects[0].lod12.has_value());
  EXPECT_TRUE(objects[0].lod12_error.empty());
  CityJsonStats stats;
  const auto features = features_of(objects, CityJsonOptions{}, stats);
  ASSERT_EQ(features.size(), 1u);
  const Json& o = city_object(features[0]);
  ASSERT_EQ(o["geometry"].size(), 1u);
  EXPECT_EQ(o["geometry"][0]["lod"], "2");
  EXPECT_FALSE(o["attributes"].contains("lod_reached"));
  EXPECT_TRUE(o["attributes"].contains("h_roof_max"));  // its top is a roof seen from above
}

// The index of a gable house in RD New, its block in the lod12 layer: GDAL reads the layer,
// its validator accepts the file, the objects layer has the LoD and the heights.
TEST(GpkgLods, TheBlocksAreALayerAndTheObjectsCarryTheirLodAndHeights) {
  std::vector<IndexObject> objects = {test::index_object("house", gable_house())};
  add_building_lods(objects, 0.01, 1e-7);
  const test::TempDir dir("csgtile-gpkg-lods-");
  const auto path = dir.path() / "index.gpkg";
  IndexOptions options;
  const auto crs = geo::crs_from_epsg(28992);
  ASSERT_TRUE(crs.ok());
  options.srs = {28992, "EPSG", 28992, crs->name, geo::crs_to_wkt1(crs.value())};
  options.to_srs = [](const Vec3& p) { return Vec3(p + Vec3(85000, 446000, 1.5)); };
  ASSERT_TRUE(write_topology_index(path, objects, options).ok());
  auto reader = TopologyIndexReader::open(path);
  ASSERT_TRUE(reader.ok()) << reader.error().message;
  auto rows = reader.value()->sql(
      "SELECT o.lod, o.h_ground, o.h_roof_50p, o.h_roof_70p, o.h_roof_max, o.roof_surfaces, "
      "l.h_ground, l.h_top FROM objects o JOIN lod12 l ON l.object_id = o.object_id");
  ASSERT_TRUE(rows.ok()) << rows.error().message;
  ASSERT_EQ(rows->size(), 1u);
  const auto& r = rows.value()[0];
  EXPECT_EQ(r[0], "2.2");
  EXPECT_NEAR(std::stod(r[1]), 1.5, 1e-9);
  EXPECT_NEAR(std::stod(r[2]), 8.0, 1e-9);
  EXPECT_NEAR(std::stod(r[3]), 8.6, 1e-9);
  EXPECT_NEAR(std::stod(r[4]), 9.5, 1e-9);
  EXPECT_EQ(r[5], "2");
  EXPECT_NEAR(std::stod(r[6]), 1.5, 1e-9);
  EXPECT_NEAR(std::stod(r[7]), 8.6, 1e-9);

  // GDAL (deploy/setup.sh); CI requires it (CSGTILE_REQUIRE_GDAL=1).
  constexpr const char* kValidator =
      "/usr/lib/python3/dist-packages/osgeo_utils/samples/validate_gpkg.py";
  if (test::run_command("ogrinfo --version", false).exit_code != 0 ||
      !std::filesystem::exists(kValidator)) {
    const char* require = std::getenv("CSGTILE_REQUIRE_GDAL");
    if (require != nullptr && std::string(require) == "1") FAIL() << "GDAL is not installed";
    GTEST_SKIP() << "GDAL's ogrinfo or validate_gpkg.py not installed; run deploy/setup.sh";
  }
  const auto info = test::run_command("ogrinfo -ro -so " + test::quoted(path) + " lod12", false);
  ASSERT_EQ(info.exit_code, 0) << info.out;
  EXPECT_NE(info.out.find("Feature Count: 1"), std::string::npos) << info.out;
  EXPECT_NE(info.out.find("Geometry: 3D Multi Polygon"), std::string::npos) << info.out;
  // The block's extent: the house's footprint in RD.
  EXPECT_NE(info.out.find("Extent: (85000.000000, 446000.000000) - (85010.000000, 446006.000000)"),
            std::string::npos)
      << info.out;
  const auto valid = test::run_command(
      std::string("/usr/bin/python3 ") + kValidator + " --extra -k " + test::quoted(path), false);
  EXPECT_EQ(valid.exit_code, 0) << valid.out;
}

// The blocks a cell's assemble job computed travel in its object records to the index job
// (city/block_records.h), which then does not compute them again: the heights, both blocks and
// the reasons come back as they were, each block moved into the run's frame as the object's
// model is; a record without blocks (written by an earlier version) says so.
TEST(BlockRecords, TheBlocksOfACellComeBackInTheRunsFrame) {
  const test::TempDir tmp("csgtile_block_records_");
  const std::filesystem::path& dir = tmp.path();
  std::filesystem::create_directories(dir / "objects");
  std::vector<IndexObject> objects = {test::index_object("house", gable_house())};
  add_building_lods(objects, 0.01, 1e-7);
  const IndexObject& cell = objects[0];
  ASSERT_TRUE(cell.lod12 && cell.lod13 && cell.heights);
  city::detail::ordered_json record;
  city::detail::ObjectBatch batch(dir);
  ASSERT_TRUE(city::detail::publish_blocks(cell, batch, record).ok());
  // Nothing is written before the batch is committed.
  EXPECT_FALSE(std::filesystem::exists(dir / record.at("lod12").get<std::string>()));
  ASSERT_TRUE(batch.commit().ok());
  city::detail::ordered_json entry = {{"blocks", record}};
  entry = city::detail::ordered_json::parse(entry.dump());  // as the queue stores it
  const Vec3 offset(250.0, -125.0, 0.0);
  IndexObject run;
  bool found = false;
  ASSERT_TRUE(
      city::detail::read_blocks(dir, entry, kernel::Location::translation(offset), run, found)
          .ok());
  ASSERT_TRUE(found);
  ASSERT_TRUE(run.heights && run.lod12 && run.lod13);
  EXPECT_EQ(run.heights->ground, cell.heights->ground);
  EXPECT_EQ(run.heights->roof_50p, cell.heights->roof_50p);
  EXPECT_EQ(run.heights->roof_70p, cell.heights->roof_70p);
  EXPECT_EQ(run.heights->roof_faces, cell.heights->roof_faces);
  EXPECT_EQ(run.lod12_error, cell.lod12_error);
  EXPECT_EQ(run.lod13_error, cell.lod13_error);
  const auto b0 = kernel::bounding_box(cell.lod12->shape);
  const auto b1 = kernel::bounding_box(run.lod12->shape);
  EXPECT_NEAR((b1.min - b0.min - offset).norm(), 0.0, 1e-9);
  EXPECT_NEAR((b1.max - b0.max - offset).norm(), 0.0, 1e-9);
  EXPECT_EQ(run.lod13->nodes.size(), cell.lod13->nodes.size());
  // Without blocks: nothing read, the object untouched.
  IndexObject old;
  ASSERT_TRUE(city::detail::read_blocks(dir, city::detail::ordered_json::object(),
                                        kernel::Location(), old, found)
                  .ok());
  EXPECT_FALSE(found);
  EXPECT_FALSE(old.lod12.has_value());
  // A block file that is not there is an error naming it.
  std::filesystem::remove_all(dir / "objects");
  EXPECT_FALSE(city::detail::read_blocks(dir, entry, kernel::Location(), run, found).ok());
}

// A cell tessellates each object once (IndexObject::mesh) for its blocks and every export:
// the blocks, CityJSON, glTF and the index (a curved object's boundary) are byte for byte
// what they are when each tessellates for itself; a mesh made at another tolerance is not
// used, and the one made at the exporters' tolerance is (an empty one shows in the output).
TEST(SharedMesh, ExportsWithTheObjectsMeshEqualThoseThatTessellateThemselves) {
  const double chordal = 0.01;
  auto dome = kernel::csg_primitive(test::cylinder_at(Vec3(30, 0, 0), 4.0, 6.0), "tower", 1e-7);
  ASSERT_TRUE(dome.ok()) << dome.error().message;
  const std::vector<IndexObject> plain = {test::index_object("house", gable_house()),
                                          test::index_object("tower", dome.value())};
  const auto with_mesh = [&](double made_at, bool empty) {
    std::vector<IndexObject> objects = plain;
    for (IndexObject& o : objects) {
      kernel::TessellationOptions t;
      t.chordal_tolerance = made_at;
      auto mesh = kernel::tessellate(o.model.shape, t);
      EXPECT_TRUE(mesh.ok());
      o.mesh = std::make_shared<const kernel::Mesh>(empty ? kernel::Mesh{} : mesh.value());
      o.mesh_tolerance = made_at;
    }
    return objects;
  };
  test::TempDir dir("shared_mesh_");
  int written = 0;
  // Everything the object's mesh reaches, as bytes.
  const auto outputs = [&](std::vector<IndexObject> objects) {
    add_building_lods(objects, chordal, 1e-7);
    std::string out;
    CityJsonOptions c;
    c.chordal_tolerance = chordal;
    auto text = cityjson_seq(objects, c);
    out += text.ok() ? text.value() : "cityjson: " + text.error().message;
    TileContentOptions t;
    t.chordal_tolerance = chordal;
    auto glb = tile_content(objects, t);
    out += glb.ok() ? glb.value().glb : "glb: " + glb.error().message;
    IndexOptions i;
    i.chordal_tolerance = chordal;
    const auto path = dir / ("index" + std::to_string(written++) + ".gpkg");
    const Failure f = write_topology_index(path, objects, i);
    out += f.ok() ? test::read_file(path) : "index: " + f.message;
    for (const IndexObject& o : objects) {
      out += o.lod12 ? kernel::write_native_model(*o.lod12) : "no lod12";
      if (o.heights) out += std::to_string(o.heights->roof_70p);
    }
    return out;
  };
  const std::string own = outputs(plain);
  ASSERT_FALSE(own.empty());
  EXPECT_EQ(outputs(with_mesh(chordal, false)), own);
  EXPECT_EQ(outputs(with_mesh(0.5, false)), own);     // another tolerance: not used
  EXPECT_NE(outputs(with_mesh(chordal, true)), own);  // the right one is used
}

}  // namespace
}  // namespace csgtile::worker
