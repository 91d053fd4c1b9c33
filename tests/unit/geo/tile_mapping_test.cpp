// TileMapping: the verified polynomial stand-in for the exact georeferencing path.

#include "csgtile/geo/tile_mapping.h"

#include <gtest/gtest.h>

#include <random>

namespace csgtile::geo {
namespace {

using kernel::BoundingBox;
using kernel::Vec3;

struct TileCase {
  int epsg;
  Vec3 centre;  // source CRS units
  double half;  // half-width of the tile, CRS units
};

BoundingBox tile_box(const TileCase& c, double z0, double z1) {
  BoundingBox b;
  b.add(Vec3(c.centre.x() - c.half, c.centre.y() - c.half, z0));
  b.add(Vec3(c.centre.x() + c.half, c.centre.y() + c.half, z1));
  return b;
}

// UTM (GeographicLib, identity datum), RD New (own projection + Helmert), LCC in US feet.
const TileCase kCases[] = {
    {32631, Vec3(640000, 5700000, 0), 500},
    {28992, Vec3(85000, 446000, 0), 500},
    {2263, Vec3(990000, 200000, 0), 1640},
};

TEST(TileMapping, AgreesWithTheExactPathInsideTheBox) {
  for (const TileCase& c : kCases) {
    SCOPED_TRACE(c.epsg);
    auto crs = crs_from_epsg(c.epsg);
    ASSERT_TRUE(crs.ok());
    auto geo = Georeferencer::create_at(crs.value(), c.centre);
    ASSERT_TRUE(geo.ok()) << geo.error().message;
    auto mapping = TileMapping::fit(geo.value(), tile_box(c, -20, 300), 1e-7);
    ASSERT_TRUE(mapping.ok()) << mapping.error().message;
    EXPECT_LE(mapping->verified_error_m(), 1e-7);
    std::mt19937_64 rng(static_cast<std::uint64_t>(c.epsg));
    std::uniform_real_distribution<double> u(-1.0, 1.0), z(-20, 300);
    double worst = 0;
    for (int i = 0; i < 20000; ++i) {
      const Vec3 p(c.centre.x() + c.half * u(rng), c.centre.y() + c.half * u(rng), z(rng));
      worst = std::max(worst, (mapping->to_local(p) - geo->to_local(p)).norm());
    }
    std::cout << "[tile mapping] EPSG:" << c.epsg << " degree " << mapping->degree()
              << ", verified " << mapping->verified_error_m() * 1e9 << " nm, random max "
              << worst * 1e9 << " nm\n";
    EXPECT_LE(worst, 2e-7);
  }
}

TEST(TileMapping, PointsOutsideTheBoxTakeTheExactPath) {
  auto crs = crs_from_epsg(32631);
  ASSERT_TRUE(crs.ok());
  const TileCase& c = kCases[0];
  auto geo = Georeferencer::create_at(crs.value(), c.centre);
  ASSERT_TRUE(geo.ok());
  auto mapping = TileMapping::fit(geo.value(), tile_box(c, 0, 100));
  ASSERT_TRUE(mapping.ok());
  for (const Vec3& p :
       {Vec3(c.centre.x() + 2000, c.centre.y(), 10), Vec3(c.centre.x(), c.centre.y(), 500)}) {
    EXPECT_EQ(mapping->to_local(p), geo->to_local(p));
  }
}

TEST(TileMapping, BulkMatchesSingleAndIsDeterministic) {
  auto crs = crs_from_epsg(28992);
  ASSERT_TRUE(crs.ok());
  const TileCase& c = kCases[1];
  auto geo = Georeferencer::create_at(crs.value(), c.centre);
  ASSERT_TRUE(geo.ok());
  auto a = TileMapping::fit(geo.value(), tile_box(c, 0, 50));
  auto b = TileMapping::fit(geo.value(), tile_box(c, 0, 50));
  ASSERT_TRUE(a.ok() && b.ok());
  std::vector<Vec3> in, out(100);
  for (int i = 0; i < 100; ++i)
    in.emplace_back(c.centre.x() - 400 + 8 * i, c.centre.y() + 3 * i, i * 0.5);
  ASSERT_TRUE(a->to_local(in, out).ok());
  for (int i = 0; i < 100; ++i) {
    EXPECT_EQ(out[static_cast<std::size_t>(i)], a->to_local(in[static_cast<std::size_t>(i)]));
    EXPECT_EQ(out[static_cast<std::size_t>(i)], b->to_local(in[static_cast<std::size_t>(i)]));
  }
}

TEST(TileMapping, BadBoxesAndBoundsAreRefused) {
  auto crs = crs_from_epsg(32631);
  ASSERT_TRUE(crs.ok());
  auto geo = Georeferencer::create_at(crs.value(), kCases[0].centre);
  ASSERT_TRUE(geo.ok());
  EXPECT_FALSE(TileMapping::fit(geo.value(), BoundingBox{}).ok());
  EXPECT_FALSE(TileMapping::fit(geo.value(), tile_box(kCases[0], 0, 1), 0.0).ok());
  // A box across half the globe cannot reach 0.1 µm with degree 12.
  BoundingBox huge;
  huge.add(Vec3(200000, 0, 0));
  huge.add(Vec3(800000, 9000000, 0));
  auto r = TileMapping::fit(geo.value(), huge, 1e-7);
  EXPECT_FALSE(r.ok());
}

}  // namespace
}  // namespace csgtile::geo
