// Building footprints through GDAL/OGR (geo/footprints.h): GeoJSON written here, reprojected
// by PROJ through GDAL; the Delft BGT buildings of ../shared/data/3dfier when present; every
// error names what is wrong.

#include "csgtile/geo/footprints.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>

#include "test_support.h"

namespace csgtile::geo {
namespace {

namespace fs = std::filesystem;

void write(const fs::path& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

// Two buildings near the RD New origin (Amersfoort): a square with a square hole, a
// multipolygon of two triangles; a line that is no footprint; a feature without geometry.
std::string sample_geojson() {
  return R"({"type": "FeatureCollection", "features": [
 {"type": "Feature", "properties": {"bag_id": "A1", "floors": 2},
  "geometry": {"type": "Polygon", "coordinates": [
    [[5.3870, 52.1550], [5.3874, 52.1550], [5.3874, 52.1553], [5.3870, 52.1553], [5.3870, 52.1550]],
    [[5.3871, 52.1551], [5.3872, 52.1551], [5.3872, 52.1552], [5.3871, 52.1551]]]}},
 {"type": "Feature", "properties": {"bag_id": "B2", "floors": 1},
  "geometry": {"type": "MultiPolygon", "coordinates": [
    [[[5.3880, 52.1550], [5.3882, 52.1550], [5.3881, 52.1552], [5.3880, 52.1550]]],
    [[[5.3890, 52.1550], [5.3892, 52.1550], [5.3891, 52.1552], [5.3890, 52.1550]]]]}},
 {"type": "Feature", "properties": {"bag_id": "C3", "floors": 0},
  "geometry": {"type": "LineString", "coordinates": [[5.39, 52.15], [5.391, 52.151]]}},
 {"type": "Feature", "properties": {"bag_id": "D4", "floors": 0}, "geometry": null}
]})";
}

TEST(Footprints, ReadsPolygonsHolesAndMultipolygonsAsStored) {
  test::TempDir dir("csgtile_footprints_");
  write(dir / "b.geojson", sample_geojson());
  auto set = read_footprints({(dir / "b.geojson").string(), "", "bag_id"}, {});
  ASSERT_TRUE(set.ok()) << set.error().message;
  ASSERT_EQ(set.value().footprints.size(), 2u);
  const Footprint& a = set.value().footprints[0];
  EXPECT_EQ(a.id, "A1");
  ASSERT_EQ(a.polygons.size(), 1u);
  EXPECT_EQ(a.polygons[0].outer.size(), 4u);  // open ring
  EXPECT_DOUBLE_EQ(a.polygons[0].outer[1].x(), 5.3874);
  EXPECT_DOUBLE_EQ(a.polygons[0].outer[2].y(), 52.1553);
  ASSERT_EQ(a.polygons[0].holes.size(), 1u);
  EXPECT_EQ(a.polygons[0].holes[0].size(), 3u);
  EXPECT_EQ(set.value().footprints[1].id, "B2");
  EXPECT_EQ(set.value().footprints[1].polygons.size(), 2u);
  // The line and the empty feature are named, with their reasons.
  ASSERT_EQ(set.value().skipped.size(), 2u);
  EXPECT_NE(set.value().skipped[0].find("C3"), std::string::npos);
  EXPECT_NE(set.value().skipped[0].find("Line String is no polygon"), std::string::npos)
      << set.value().skipped[0];
  EXPECT_NE(set.value().skipped[1].find("no geometry"), std::string::npos);
  EXPECT_FALSE(set.value().source_crs.empty());  // GeoJSON is WGS 84
}

TEST(Footprints, ReprojectsToTheRunCrsAndFiltersByItsBounds) {
  test::TempDir dir("csgtile_footprints_");
  write(dir / "b.geojson", sample_geojson());
  // RD New (+ NAP heights, whose vertical part is ignored for outlines).
  auto set = read_footprints({(dir / "b.geojson").string(), "", "bag_id"},
                             {"EPSG:28992+5709", std::nullopt});
  ASSERT_TRUE(set.ok()) << set.error().message;
  ASSERT_EQ(set.value().footprints.size(), 2u);
  // The RD origin (155000, 463000) is at about 52.15517 N, 5.38721 E: the square's corner
  // (5.3870, 52.1550) lies some 15 m west and 19 m south of it.
  const kernel::Vec2 c = set.value().footprints[0].polygons[0].outer[0];
  EXPECT_NEAR(c.x(), 155000.0 - 14.2, 3.0);
  EXPECT_NEAR(c.y(), 463000.0 - 19.4, 3.0);
  // A square of 0.0004° × 0.0003° is about 27.4 m × 33.4 m there.
  const auto& o = set.value().footprints[0].polygons[0].outer;
  EXPECT_NEAR((o[1] - o[0]).norm(), 27.4, 0.3);
  EXPECT_NEAR((o[2] - o[1]).norm(), 33.4, 0.3);
  // Bounds in the target CRS keep only what meets them.
  auto near =
      read_footprints({(dir / "b.geojson").string(), "", "bag_id"},
                      {"EPSG:28992", std::array<double, 4>{154900, 462900, 155010, 463100}});
  ASSERT_TRUE(near.ok()) << near.error().message;
  ASSERT_EQ(near.value().footprints.size(), 1u);
  EXPECT_EQ(near.value().footprints[0].id, "A1");
  // ... and cut to them: A1 ends at x = 155005 (its hole, west of it, stays).
  FootprintQuery cut{"EPSG:28992", std::array<double, 4>{154900, 462900, 155005, 463100}};
  cut.clip = {*cut.bbox};
  auto clipped = read_footprints({(dir / "b.geojson").string(), "", "bag_id"}, cut);
  ASSERT_TRUE(clipped.ok()) << clipped.error().message;
  ASSERT_EQ(clipped.value().footprints.size(), 1u);
  const FootprintPolygon& p = clipped.value().footprints[0].polygons.at(0);
  double x_max = -INFINITY, x_min = INFINITY;
  for (const kernel::Vec2& q : p.outer)
    x_max = std::max(x_max, q.x()), x_min = std::min(x_min, q.x());
  EXPECT_DOUBLE_EQ(x_max, 155005.0);
  EXPECT_NEAR(x_min, 155000.0 - 14.2, 3.0);
  EXPECT_EQ(p.holes.size(), 1u);
  // Cut to the union of two boxes meeting at x = 155002 (two tiles' extents): one polygon, no
  // slit along the seam; and also cut to the first box alone (Footprint::cut), its envelope
  // the whole feature's.
  cut.clip = {{154900, 462900, 155002, 463100}, {155002, 462900, 155005, 463100}};
  cut.cut = std::array<double, 4>{154900, 462900, 155002, 463100};
  auto seam = read_footprints({(dir / "b.geojson").string(), "", "bag_id"}, cut);
  ASSERT_TRUE(seam.ok()) << seam.error().message;
  ASSERT_EQ(seam.value().footprints.size(), 1u);
  const Footprint& f = seam.value().footprints[0];
  ASSERT_EQ(f.polygons.size(), 1u);
  EXPECT_EQ(f.polygons[0].outer.size(), p.outer.size());
  ASSERT_EQ(f.cut.size(), 1u);
  double cut_max = -INFINITY;
  for (const kernel::Vec2& q : f.cut[0].outer) cut_max = std::max(cut_max, q.x());
  EXPECT_DOUBLE_EQ(cut_max, 155002.0);
  EXPECT_GT(f.envelope[2], 155005.0);
  EXPECT_NEAR(f.envelope[0], x_min, 1e-6);
}

TEST(Footprints, ErrorsNameWhatIsWrong) {
  test::TempDir dir("csgtile_footprints_");
  write(dir / "b.geojson", sample_geojson());
  const std::string path = (dir / "b.geojson").string();
  auto missing = read_footprints({(dir / "none.gpkg").string(), "", ""}, {});
  ASSERT_FALSE(missing.ok());
  EXPECT_EQ(missing.error().code, kernel::ErrorCode::IoError);
  EXPECT_NE(missing.error().message.find("none.gpkg"), std::string::npos);
  auto layer = read_footprints({path, "panden", ""}, {});
  ASSERT_FALSE(layer.ok());
  EXPECT_NE(layer.error().message.find("no layer 'panden'"), std::string::npos);
  auto field = read_footprints({path, "", "identificatie"}, {});
  ASSERT_FALSE(field.ok());
  EXPECT_NE(field.error().message.find("bag_id, floors"), std::string::npos)
      << field.error().message;
  auto crs = read_footprints({path, "", ""}, {"EPSG:999999", std::nullopt});
  ASSERT_FALSE(crs.ok());
  EXPECT_NE(crs.error().message.find("EPSG:999999"), std::string::npos);
  write(dir / "bad.geojson", "{\"type\": \"FeatureCollection\", \"features\": [");
  auto broken = read_footprints({(dir / "bad.geojson").string(), "", ""}, {});
  EXPECT_FALSE(broken.ok());
  // A check reads no feature but finds what a read would.
  FootprintQuery check;
  check.target_crs = "EPSG:28992";
  check.check_only = true;
  auto checked = read_footprints({path, "", "bag_id"}, check);
  ASSERT_TRUE(checked.ok()) << checked.error().message;
  EXPECT_TRUE(checked.value().footprints.empty());
  EXPECT_FALSE(read_footprints({path, "", "identificatie"}, check).ok());
  // Without an id attribute, the feature ids.
  auto fids = read_footprints({path, "", ""}, {});
  ASSERT_TRUE(fids.ok());
  EXPECT_EQ(fids.value().footprints[0].id, "0");
}

TEST(Footprints, DelftBgtBuildings) {
  const fs::path path = test::shared_dir() / "data" / "3dfier" / "bgt_pand.sqlite";
  if (!fs::exists(path)) GTEST_SKIP() << path << " is absent (../shared/data/3dfier)";
  auto set = read_footprints({path.string(), "buildingpart", "identificatiebagpnd"},
                             {"EPSG:28992+5709", std::nullopt});
  ASSERT_TRUE(set.ok()) << set.error().message;
  EXPECT_EQ(set.value().footprints.size() + set.value().skipped.size(), 160u);
  double area = 0.0;
  for (const Footprint& f : set.value().footprints) {
    EXPECT_FALSE(f.id.empty());
    for (const FootprintPolygon& p : f.polygons) {
      double a = 0.0;
      for (std::size_t i = 0; i < p.outer.size(); ++i) {
        const kernel::Vec2& u = p.outer[i];
        const kernel::Vec2& v = p.outer[(i + 1) % p.outer.size()];
        a += u.x() * v.y() - v.x() * u.y();
        // Same CRS: the stored RD coordinates, inside the layer's extent.
        EXPECT_GE(u.x(), 84825.0);
        EXPECT_LE(u.x(), 85057.0);
      }
      area += std::abs(a) / 2.0;
    }
  }
  EXPECT_GT(area, 5000.0);
}

}  // namespace
}  // namespace csgtile::geo
