// Unclassified tiles (issue #18 item 1): a tree beside a house, both without classes, and a
// raised street beside a house. The tree's crown returns several times per pulse (or, without
// returns, scatters its normals), the house's roof once on its planes: the fit makes the house and
// nothing over the tree; with vegetation off, the tree's points are fitted too.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <vector>

#include "csgtile/fit/segment.h"
#include "csgtile/kernel/mass_properties.h"
#include "csgtile/kernel/primitives.h"
#include "fit_clouds.h"

namespace csgtile::fit {
namespace {

using kernel::Vec3;
using testing::Cloud;

struct Scene {
  std::vector<Vec3> points;
  std::vector<std::uint8_t> returns;
};

// Ground over [-15, 35] × [-15, 25]; a flat-roofed house of 10 × 8 m, 6 m high, at the
// origin (roof points and two walls, single returns); a tree beside it: a crown of radius 3 m
// centred 5 m up at (22, 4): mostly its upper surface, leaves ±0.25 m around it, some points
// inside (several returns each).
Scene tree_beside_house() {
  Scene s;
  auto add = [&](const Cloud& c, std::uint8_t returns) {
    s.points.insert(s.points.end(), c.points.begin(), c.points.end());
    s.returns.resize(s.points.size(), returns);
  };
  add(testing::rectangle_cloud(Vec3(-15, -15, 0), Vec3(50, 0, 0), Vec3(0, 40, 0), 0.5, 0.02, 3), 1);
  add(testing::rectangle_cloud(Vec3(0, 0, 6), Vec3(10, 0, 0), Vec3(0, 8, 0), 0.3, 0.02, 4), 1);
  add(testing::rectangle_cloud(Vec3(0, 0, 0), Vec3(10, 0, 0), Vec3(0, 0, 6), 0.5, 0.02, 5), 1);
  add(testing::rectangle_cloud(Vec3(0, 8, 0), Vec3(0, 0, 6), Vec3(10, 0, 0), 0.5, 0.02, 6), 1);
  testing::Draw d(7);
  Cloud crown;
  for (int i = 0; i < 5000; ++i) {
    // The crown as the air sees it: mostly its upper surface (a dome, leaves ±0.25 m around
    // it), some points inside it.
    Vec3 q(2 * d.uniform() - 1, 2 * d.uniform() - 1, d.uniform());
    if (q.norm() > 1.0 || q.norm() < 1e-3) continue;
    const double r = d.uniform() < 0.8 ? 3.0 + 0.5 * (d.uniform() - 0.5) : 3.0 * d.uniform();
    crown.points.push_back(Vec3(22, 4, 5) + r * q.normalized());
    crown.normals.push_back(Vec3::UnitZ());
  }
  add(crown, 3);
  return s;
}

int primitives_over(const FitOutput& out, double x0, double x1) {
  int n = 0;
  for (const auto& p : out.primitives) {
    const auto solid = kernel::build_primitive(p.spec);
    if (!solid.ok()) continue;
    const kernel::BoundingBox b = kernel::bounding_box(solid.value());
    if (b.max.x() > x0 && b.min.x() < x1) ++n;
  }
  return n;
}

TEST(FitVegetation, ATreeBesideAHouseIsNotFitted) {
  const Scene s = tree_beside_house();
  FitPipelineOptions o;
  o.outliers.enabled = false;
  const auto out = fit_point_cloud(s.points, {}, o, {}, s.returns);
  ASSERT_TRUE(out.ok()) << out.error().message;
  EXPECT_GT(out->vegetation_points, 1500);
  EXPECT_GE(primitives_over(*out, -0.5, 10.5), 1);  // the house
  EXPECT_EQ(primitives_over(*out, 18.0, 26.0), 0);  // nothing over the tree
  // Without returns (a PLY, an XYZ): the crown's scattered normals alone.
  const auto rough = fit_point_cloud(s.points, {}, o);
  ASSERT_TRUE(rough.ok());
  EXPECT_GE(primitives_over(*rough, -0.5, 10.5), 1);
  EXPECT_EQ(primitives_over(*rough, 18.0, 26.0), 0);
  // Vegetation off: the tree's points are a region of their own, given to the RANSAC.
  o.vegetation.enabled = false;
  const auto all = fit_point_cloud(s.points, {}, o, {}, s.returns);
  ASSERT_TRUE(all.ok());
  EXPECT_EQ(all->vegetation_points, 0);
  EXPECT_GT(all->regions, out->regions);
}

// A tile classified for its ground only (class 2; the house and the tree unclassified, 1, as
// many national deliveries are): the classes do not tell the vegetation, so it is found from
// the points as on an unclassified tile — nothing over the tree.
TEST(FitVegetation, ATileClassifiedForItsGroundOnlyStillLosesItsTree) {
  const Scene s = tree_beside_house();
  std::vector<std::uint8_t> classes(s.points.size(), 1);
  for (std::size_t i = 0; i < s.points.size(); ++i) {
    if (std::abs(s.points[i].z()) < 0.1 && (s.points[i].x() < -0.5 || s.points[i].x() > 10.5 ||
                                            s.points[i].y() < -0.5 || s.points[i].y() > 8.5))
      classes[i] = 2;
  }
  FitPipelineOptions o;
  o.outliers.enabled = false;
  const auto out = fit_point_cloud(s.points, classes, o, {}, s.returns);
  ASSERT_TRUE(out.ok()) << out.error().message;
  EXPECT_GT(out->vegetation_points, 1500);
  EXPECT_GE(primitives_over(*out, -0.5, 10.5), 1);  // the house
  EXPECT_EQ(primitives_over(*out, 18.0, 26.0), 0);  // nothing over the tree
  // Had the tile classed its vegetation (class 5 for the crown), the classes would decide.
  std::vector<std::uint8_t> with_trees = classes;
  for (std::size_t i = 0; i < s.points.size(); ++i) {
    if (s.returns[i] == 3) with_trees[i] = 5;
  }
  const auto classed = fit_point_cloud(s.points, with_trees, o, {}, s.returns);
  ASSERT_TRUE(classed.ok());
  EXPECT_EQ(classed->vegetation_points, 0);
  EXPECT_EQ(primitives_over(*classed, 18.0, 26.0), 0);
}

// A street raised 1.2 m over the terrain beside it (a quay along a canal: wider than the
// ground filter's window sees as terrain, narrower than the window it is opened with) is no
// building: no slab over it; the house beside it is modelled.
TEST(FitUnclassified, RaisedGroundIsNoBuilding) {
  std::vector<Vec3> points;
  auto add = [&](const Cloud& c) { points.insert(points.end(), c.points.begin(), c.points.end()); };
  add(testing::rectangle_cloud(Vec3(-15, -15, 0), Vec3(60, 0, 0), Vec3(0, 40, 0), 0.5, 0.02, 3));
  add(testing::rectangle_cloud(Vec3(0, 0, 6), Vec3(10, 0, 0), Vec3(0, 8, 0), 0.3, 0.02, 4));
  // The quay: 20 × 6 m at 1.2 m (its wall, facing the water, is barely seen from the air).
  add(testing::rectangle_cloud(Vec3(18, 0, 1.2), Vec3(20, 0, 0), Vec3(0, 6, 0), 0.3, 0.02, 8));
  FitPipelineOptions o;
  o.outliers.enabled = false;
  o.ground.use_classification = false;
  const auto out = fit_point_cloud(points, {}, o);
  ASSERT_TRUE(out.ok()) << out.error().message;
  EXPECT_GE(primitives_over(*out, -0.5, 10.5), 1);  // the house
  std::string found;
  for (const auto& p : out->primitives) {
    const auto solid = kernel::build_primitive(p.spec);
    if (!solid.ok()) continue;
    const kernel::BoundingBox b = kernel::bounding_box(solid.value());
    found += std::string(kernel::primitive_type_name(p.spec.type)) + " [" +
             std::to_string(b.min.x()) + ", " + std::to_string(b.max.x()) + "] z [" +
             std::to_string(b.min.z()) + ", " + std::to_string(b.max.z()) + "]; ";
  }
  for (const auto& r : out->rejected) found += "| " + r.what + ": " + r.reason + " ";
  EXPECT_EQ(primitives_over(*out, 17.0, 39.0), 0) << found;  // nothing over the quay
  bool named = false;
  for (const auto& r : out->rejected)
    named = named || r.reason.find("raised ground") != std::string::npos;
  EXPECT_TRUE(named);
}

}  // namespace
}  // namespace csgtile::fit
