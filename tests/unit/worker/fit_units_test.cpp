// A tile whose CRS counts in feet is fitted as the same tile in metres (city/fit_tile.cpp):
// every fit option is a length in metres, so the points are fitted in metres and the
// primitives given back in feet. Before, the fit took the feet for metres: its 0.3 m ground
// height, its 2 m building height and its RANSAC epsilon were a third too small, and a tile in
// feet gave other buildings than the same tile in metres. Read from ../shared/data in place.

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>

#include "city/fit_tile.h"
#include "csgtile/geo/las.h"
#include "csgtile/geo/point_reader.h"
#include "csgtile/kernel/mass_properties.h"
#include "test_support.h"

namespace csgtile::worker::city {
namespace {

constexpr double kFoot = 0.3048;
// RD New with its coordinates in international feet: what a tile in feet looks like to the fit.
constexpr const char* kRdInFeet =
    "+proj=sterea +lat_0=52.15616055555555 +lon_0=5.38763888888889 +k=0.9999079 +x_0=155000 "
    "+y_0=463000 +ellps=bessel +units=ft +type=crs";

double volume_of(const geo::ScenePrimitive& p) {
  auto solid = kernel::build_primitive(p.spec);
  EXPECT_TRUE(solid.ok()) << p.id;
  return solid.ok() ? kernel::shape_volume(solid.value()) : NAN;
}

TEST(FitUnits, ATileInFeetIsFittedAsTheSameTileInMetres) {
  const auto metres = test::shared_dir() / "data" / "ams" / "ahn_2386_9702.las";
  if (!std::filesystem::exists(metres)) GTEST_SKIP() << metres << " absent (../shared/data)";
  // The same points in feet, the same integers in the file (the scale in feet).
  auto reader = geo::open_point_file(metres);
  ASSERT_TRUE(reader.ok());
  geo::PointBatch all, batch;
  for (;;) {
    auto n = reader.value()->read(batch, 1 << 16);
    ASSERT_TRUE(n.ok());
    if (n.value() == 0) break;
    all.points.insert(all.points.end(), batch.points.begin(), batch.points.end());
  }
  for (geo::Point& p : all.points) p.x /= kFoot, p.y /= kFoot, p.z /= kFoot;
  test::TempDir dir("csgtile_fit_units_");
  geo::LasWriteOptions w;
  w.version_minor = 2;
  w.point_format = 1;
  w.scale = {0.001 / kFoot, 0.001 / kFoot, 0.001 / kFoot};
  ASSERT_TRUE(geo::write_las(dir / "feet.las", w, all).ok());

  const fit::FitPipelineOptions options = fit_options(config::Config{});
  FittedTile in_metres, in_feet;
  ASSERT_TRUE(fit_tile(metres, "m", options, "EPSG:28992", in_metres).ok());
  Failure f = fit_tile(dir / "feet.las", "ft", options, kRdInFeet, in_feet);
  ASSERT_TRUE(f.ok()) << f.message;

  FittedTile as_metres;  // what the fit did before: the feet taken for metres
  ASSERT_TRUE(fit_tile(dir / "feet.las", "ft", options, "EPSG:28992", as_metres).ok());
  auto total = [](const FittedTile& t, double unit) {
    double v = 0.0;
    for (const auto& p : t.output.primitives) v += volume_of(p);
    return v * unit * unit * unit;
  };
  const double vm = total(in_metres, 1.0), vft = total(in_feet, kFoot),
               vold = total(as_metres, kFoot);
  std::printf(
      "[units] metres: %zu primitives, %.1f m3; feet: %zu, %.1f m3; feet taken for "
      "metres: %zu, %.1f m3\n",
      in_metres.output.primitives.size(), vm, in_feet.output.primitives.size(), vft,
      as_metres.output.primitives.size(), vold);
  // Not bit for bit: the frame's origin (the floor of the smallest x and y) is a whole foot,
  // not a whole metre, and the fit's grids (ground, voxels, connectivity) sit on it. Before,
  // the tile in feet gave 121 primitives and 5 % more volume; now 61 and 1 % less.
  const double n = static_cast<double>(in_metres.output.primitives.size());
  EXPECT_NEAR(static_cast<double>(in_feet.output.primitives.size()), n, 0.1 * n);
  EXPECT_NEAR(vft, vm, 0.03 * vm);
  EXPECT_EQ(in_feet.output.ground_points, in_metres.output.ground_points);
  EXPECT_EQ(in_feet.output.fitted_points, in_metres.output.fitted_points);
  EXPECT_EQ(in_feet.output.structure_points.size(), in_metres.output.structure_points.size());
}

TEST(FitUnits, AGeographicTileFailsNamingWhy) {
  const auto path = test::shared_dir() / "data" / "pdal" / "epsg_4326.las";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " absent (../shared/data)";
  FittedTile out;
  Failure f = fit_tile(path, "g", fit_options(config::Config{}), "", out);
  ASSERT_FALSE(f.ok());
  EXPECT_EQ(f.code, ErrorCode::InputInvalid);
  EXPECT_NE(f.message.find("geographic"), std::string::npos) << f.message;
}

}  // namespace
}  // namespace csgtile::worker::city
