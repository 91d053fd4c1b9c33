// The segmentation stages one by one (outliers, voxels, normals, ground, clusters, region
// growing) and the whole fit pipeline: primitives found, counts kept, and the same bytes for the
// same seed.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stop_token>

#include "csgtile/fit/segment.h"
#include "csgtile/geo/scene.h"
#include "csgtile/kernel/mass_properties.h"
#include "fit_clouds.h"

namespace csgtile::fit {
namespace {

using geo::Scene;
using geo::scene_to_json;
using kernel::PrimitiveType;
using kernel::Vec3;
using testing::Cloud;

TEST(FitSegment, StatisticalOutliersAreRemoved) {
  Cloud c = testing::rectangle_cloud(Vec3::Zero(), Vec3(2, 0, 0), Vec3(0, 2, 0), 0.02, 0.001, 1);
  const std::size_t surface = c.points.size();
  c.points.emplace_back(1.0, 1.0, 3.0);
  c.points.emplace_back(-4.0, 1.0, 0.0);
  const auto kept = remove_statistical_outliers(c.points, {});
  EXPECT_GE(kept.size(), surface * 98 / 100);
  EXPECT_EQ(std::count(kept.begin(), kept.end(), static_cast<std::uint32_t>(surface)), 0);
  EXPECT_EQ(std::count(kept.begin(), kept.end(), static_cast<std::uint32_t>(surface + 1)), 0);
  EXPECT_TRUE(std::is_sorted(kept.begin(), kept.end()));
}

// Among a subset of the points (by index, no copy), the filter keeps what it keeps of a copy
// of that subset, as positions in the subset; points outside the subset take no part.
TEST(FitSegment, StatisticalOutliersOfASubsetAreThoseOfItsCopy) {
  Cloud c = testing::rectangle_cloud(Vec3::Zero(), Vec3(2, 0, 0), Vec3(0, 2, 0), 0.02, 0.001, 3);
  c.points.emplace_back(1.0, 1.0, 3.0);
  c.points.emplace_back(std::nan(""), 0.0, 0.0);
  c.points.emplace_back(-4.0, 1.0, 0.0);
  std::vector<std::uint32_t> subset;
  std::vector<Vec3> copy;
  for (std::uint32_t i = 0; i < c.points.size(); ++i) {
    if (i % 3 == 1 && i + 3 < c.points.size()) continue;  // left out, the outliers kept in
    subset.push_back(i);
    copy.push_back(c.points[i]);
  }
  const auto expected = remove_statistical_outliers(copy, {});
  const auto kept = remove_statistical_outliers(c.points, subset, {});
  EXPECT_EQ(kept, expected);
  EXPECT_LT(kept.size(), subset.size() - 2);  // the three outliers (and maybe a few more) out
}

TEST(FitSegment, VoxelDownsamplingKeepsOnePointPerVoxel) {
  const Cloud c =
      testing::rectangle_cloud(Vec3::Zero(), Vec3(1, 0, 0), Vec3(0, 1, 0), 0.005, 0.0, 2);
  const auto down = voxel_downsample(c.points, {0.1});
  EXPECT_LE(down.size(), 121U);
  EXPECT_GE(down.size(), 100U);
  EXPECT_EQ(voxel_downsample(c.points, {0.0}).size(), c.points.size());
}

TEST(FitSegment, NormalsOfAPlaneAreItsNormal) {
  const Cloud c =
      testing::rectangle_cloud(Vec3::Zero(), Vec3(1, 0, 0), Vec3(0, 0.6, 0.8), 0.02, 0.0005, 3);
  const auto normals = estimate_normals(c.points, {});
  ASSERT_EQ(normals.size(), c.points.size());
  for (const auto& n : normals) EXPECT_GT(std::abs(n.dot(Vec3(0, -0.8, 0.6))), 0.99);
}

TEST(FitSegment, GroundFromClassesOrFromTheMorphologicalFilter) {
  Cloud c =
      testing::rectangle_cloud(Vec3(-20, -20, 0), Vec3(40, 0, 0), Vec3(0, 40, 0), 0.5, 0.01, 4);
  const std::size_t ground = c.points.size();
  c.append(testing::rectangle_cloud(Vec3(-3, -3, 6), Vec3(6, 0, 0), Vec3(0, 6, 0), 0.2, 0.01, 5));
  std::vector<std::uint8_t> classes(c.points.size(), 6);
  for (std::size_t i = 0; i < ground; ++i) classes[i] = 2;
  const auto by_class = ground_mask(c.points, classes, {});
  for (std::size_t i = 0; i < c.points.size(); ++i) ASSERT_EQ(by_class[i], i < ground ? 1 : 0);
  const auto by_filter = ground_mask(c.points, {}, {});
  std::size_t wrong = 0;
  for (std::size_t i = 0; i < c.points.size(); ++i) wrong += (by_filter[i] != (i < ground ? 1 : 0));
  EXPECT_EQ(wrong, 0U);
}

TEST(FitSegment, ClustersAreSeparatedAndOrderedBySize) {
  Cloud c = testing::rectangle_cloud(Vec3(5, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), 0.02, 0.0, 6);
  const std::size_t first = c.points.size();
  c.append(testing::rectangle_cloud(Vec3(0, 0, 0), Vec3(2, 0, 0), Vec3(0, 1, 0), 0.02, 0.0, 7));
  const auto clusters = euclidean_clusters(c.points, {});
  ASSERT_EQ(clusters.size(), 2U);
  EXPECT_EQ(clusters[0].size(), c.points.size() - first);  // the larger one first
  EXPECT_EQ(clusters[1].size(), first);  // random points, but none farther than the tolerance
  EXPECT_EQ(clusters[1].front(), 0U);
}

// Region growing with our own normals and curvature, as the pipeline runs it.
std::vector<std::vector<std::uint32_t>> grow(const Cloud& c, const RegionGrowingOptions& o) {
  return region_growing(c.points, estimate_normals(c.points, {}), o);
}

RegionGrowingOptions growing_on() {
  RegionGrowingOptions o;
  o.enabled = true;
  return o;
}

TEST(FitSegment, RegionGrowingSplitsTwoPlanesAtARightAngle) {
  // A floor and a wall sharing the edge along x: one Euclidean cluster, two smooth pieces.
  Cloud c = testing::rectangle_cloud(Vec3::Zero(), Vec3(2, 0, 0), Vec3(0, 2, 0), 0.02, 0.001, 20);
  const std::size_t floor = c.points.size();
  c.append(testing::rectangle_cloud(Vec3::Zero(), Vec3(2, 0, 0), Vec3(0, 0, 2), 0.02, 0.001, 21));
  ASSERT_EQ(euclidean_clusters(c.points, {}).size(), 1U);
  const auto regions = grow(c, growing_on());
  ASSERT_EQ(regions.size(), 2U);
  for (const auto& r : regions) {
    EXPECT_TRUE(std::is_sorted(r.begin(), r.end()));
    const auto on_floor =
        std::count_if(r.begin(), r.end(), [&](std::uint32_t i) { return i < floor; });
    // Each region is (nearly) one plane; only points at the edge may go either way.
    const auto major = std::max<std::size_t>(static_cast<std::size_t>(on_floor),
                                             r.size() - static_cast<std::size_t>(on_floor));
    EXPECT_GE(major, r.size() * 99 / 100);
    EXPECT_GE(r.size(), floor * 9 / 10);
  }
  EXPECT_GE(regions[0].size(), regions[1].size());
}

TEST(FitSegment, RegionGrowingKeepsASmoothCylinderWhole) {
  const Cloud c = testing::cylinder_cloud(Vec3::Zero(), Vec3::UnitZ(), 0.3, 2.0, 0.0,
                                          2.0 * std::numbers::pi, 8000, 0.001, 22);
  const auto regions = grow(c, growing_on());
  ASSERT_EQ(regions.size(), 1U);
  EXPECT_GE(regions[0].size(), c.points.size() * 95 / 100);
}

TEST(FitSegment, RegionGrowingDisabledGivesOneRegion) {
  Cloud c = testing::rectangle_cloud(Vec3::Zero(), Vec3(2, 0, 0), Vec3(0, 2, 0), 0.02, 0.001, 23);
  c.append(testing::rectangle_cloud(Vec3::Zero(), Vec3(2, 0, 0), Vec3(0, 0, 2), 0.02, 0.001, 24));
  const auto regions = grow(c, {});
  ASSERT_EQ(regions.size(), 1U);
  EXPECT_EQ(regions[0].size(), c.points.size());
  EXPECT_EQ(regions[0].front(), 0U);
}

TEST(FitSegment, RegionGrowingOnDegenerateInputGivesNoRegion) {
  const RegionGrowingOptions on = growing_on();
  EXPECT_TRUE(region_growing({}, {}, on).empty());
  std::vector<Vec3> line;
  for (int i = 0; i < 200; ++i) line.emplace_back(0.01 * i, 0.02 * i, 0.0);
  EXPECT_TRUE(region_growing(line, estimate_normals(line, {}), on).empty());
  const std::vector<Vec3> same(100, Vec3(1, 2, 3));
  EXPECT_TRUE(region_growing(same, estimate_normals(same, {}), on).empty());
  // Sizes that do not match, and NaNs, are refused or skipped, never a crash.
  EXPECT_TRUE(region_growing(line, std::vector<Vec3>(3, Vec3::UnitZ()), on).empty());
  std::vector<Vec3> nan_normals(line.size(), Vec3(NAN, 0, 1));
  EXPECT_TRUE(region_growing(line, nan_normals, on).empty());
}

TEST(FitSegment, RegionGrowingIsDeterministic) {
  Cloud c = testing::rectangle_cloud(Vec3::Zero(), Vec3(2, 0, 0), Vec3(0, 2, 0), 0.02, 0.003, 25);
  c.append(testing::rectangle_cloud(Vec3::Zero(), Vec3(2, 0, 0), Vec3(0, 0, 2), 0.02, 0.003, 26));
  c.append(testing::cylinder_cloud(Vec3(1, 1, 0), Vec3::UnitZ(), 0.2, 1.5, 0.0,
                                   2.0 * std::numbers::pi, 3000, 0.003, 27));
  const auto a = grow(c, growing_on());
  EXPECT_FALSE(a.empty());
  EXPECT_EQ(a, grow(c, growing_on()));
}

Cloud small_scene() {
  // A column under a beam seen from three sides, a sphere, and a ground plane.
  Cloud c =
      testing::rectangle_cloud(Vec3(-5, -5, 0), Vec3(10, 0, 0), Vec3(0, 10, 0), 0.1, 0.003, 10);
  c.append(testing::cylinder_cloud(Vec3(0, 0, 0), Vec3::UnitZ(), 0.15, 3.7, 0.0,
                                   2.0 * std::numbers::pi, 6000, 0.003, 11));
  const Vec3 corner(0.2, -0.1, 3.7);
  c.append(testing::rectangle_cloud(corner, Vec3(0, 0, 0.3), Vec3(2.5, 0, 0), 0.015, 0.003, 12));
  c.append(testing::rectangle_cloud(corner + Vec3(0, 0.2, 0), Vec3(2.5, 0, 0), Vec3(0, 0, 0.3),
                                    0.015, 0.003, 13));
  c.append(testing::rectangle_cloud(corner, Vec3(2.5, 0, 0), Vec3(0, 0.2, 0), 0.015, 0.003, 14));
  c.append(testing::sphere_cloud(Vec3(-3, 2, 1.5), 1.0, -0.5, 5000, 0.003, 15));
  return c;
}

// The pipeline options of these scenes of a few metres: 1 cm inliers, a 0.5 m ground grid.
FitPipelineOptions small_scene_options() {
  FitPipelineOptions o;
  o.ransac.epsilon = 0.01;
  o.ground.cell = 0.5;
  o.ground.window = 4.0;
  return o;
}

TEST(FitSegment, PipelineFindsTheColumnTheBeamAndTheSphere) {
  const Cloud c = small_scene();
  FitPipelineOptions o = small_scene_options();
  const auto out = fit_point_cloud(c.points, {}, o);
  ASSERT_TRUE(out.ok()) << out.error().message;
  EXPECT_EQ(out->per_type[static_cast<int>(PrimitiveType::Cylinder)], 1);
  EXPECT_EQ(out->per_type[static_cast<int>(PrimitiveType::Box)], 1);
  EXPECT_EQ(out->per_type[static_cast<int>(PrimitiveType::Sphere)], 1);
  EXPECT_GT(out->ground_points, 9000);
  EXPECT_EQ(out->unassigned_points, out->fitted_points - out->assigned_points);
  EXPECT_LT(out->unassigned_points, out->fitted_points / 10);
}

// A fit asked to stop (a worker shutting down) returns Cancelled, naming the stage; a time
// limit the fit stays within changes nothing.
TEST(FitSegment, AStopRequestCancelsTheFit) {
  const Cloud c = small_scene();
  FitPipelineOptions o = small_scene_options();
  std::stop_source source;
  source.request_stop();
  o.interrupt.stop = source.get_token();
  const auto stopped = fit_point_cloud(c.points, {}, o);
  ASSERT_FALSE(stopped.ok());
  EXPECT_EQ(stopped.error().code, kernel::ErrorCode::Cancelled);
  EXPECT_NE(stopped.error().message.find("stopped on request before the fit's outliers stage"),
            std::string::npos)
      << stopped.error().message;
  o.interrupt = kernel::Interrupt{}.within(3600);
  const auto limited = fit_point_cloud(c.points, {}, o);
  o.interrupt = {};
  const auto free = fit_point_cloud(c.points, {}, o);
  ASSERT_TRUE(limited.ok() && free.ok());
  Scene a, b;
  a.primitives = limited->primitives;
  b.primitives = free->primitives;
  EXPECT_FALSE(a.primitives.empty());
  EXPECT_EQ(scene_to_json(a), scene_to_json(b));
}

// With classes.keep, only the kept classes are fitted: the sphere labelled vegetation (5)
// is left out and counted, the column and beam (6) are fitted; ground stays class 2.
TEST(FitSegment, ClassFilterKeepsOnlyTheNamedClasses) {
  const Cloud c = small_scene();
  const std::size_t ground = 10 * 10 * 100;  // the first cloud: 10 m × 10 m at 0.1 m
  std::vector<std::uint8_t> classes(c.points.size(), 6);
  std::fill(classes.begin(), classes.begin() + static_cast<std::ptrdiff_t>(ground), 2);
  const std::size_t sphere = c.points.size() - 5000;  // the last cloud
  std::fill(classes.begin() + static_cast<std::ptrdiff_t>(sphere), classes.end(), 5);
  FitPipelineOptions o;
  o.ransac.epsilon = 0.01;
  o.classes.keep = {6};
  const auto out = fit_point_cloud(c.points, classes, o);
  ASSERT_TRUE(out.ok()) << out.error().message;
  EXPECT_EQ(out->other_class_points, 5000);
  EXPECT_EQ(out->ground_points, static_cast<long long>(ground));
  EXPECT_EQ(out->per_type[static_cast<int>(PrimitiveType::Sphere)], 0);
  EXPECT_EQ(out->per_type[static_cast<int>(PrimitiveType::Cylinder)], 1);
  EXPECT_EQ(out->per_type[static_cast<int>(PrimitiveType::Box)], 1);
  // An input never classified (every point class 1) keeps all its points.
  const std::vector<std::uint8_t> unclassified(c.points.size(), 1);
  const auto kept = fit_point_cloud(c.points, unclassified, o);
  ASSERT_TRUE(kept.ok());
  EXPECT_EQ(kept->other_class_points, 0);
  EXPECT_EQ(kept->per_type[static_cast<int>(PrimitiveType::Sphere)], 1);
  // Without the filter the sphere is fitted again.
  o.classes.keep.clear();
  o.classes.drop.clear();
  const auto all = fit_point_cloud(c.points, classes, o);
  ASSERT_TRUE(all.ok());
  EXPECT_EQ(all->other_class_points, 0);
  EXPECT_EQ(all->per_type[static_cast<int>(PrimitiveType::Sphere)], 1);
}

// The defaults on a tile classified without buildings (ground 2, unclassified 1, vegetation
// 5): no keep class is present, so every non-ground point but the dropped vegetation is
// fitted — the column and beam (1) are, the tree-like sphere (5) is not.
TEST(FitSegment, ClassifiedTileWithoutBuildingClassDropsOnlyVegetation) {
  const Cloud c = small_scene();
  const std::size_t ground = 10 * 10 * 100;
  std::vector<std::uint8_t> classes(c.points.size(), 1);
  std::fill(classes.begin(), classes.begin() + static_cast<std::ptrdiff_t>(ground), 2);
  const std::size_t sphere = c.points.size() - 5000;
  std::fill(classes.begin() + static_cast<std::ptrdiff_t>(sphere), classes.end(), 5);
  FitPipelineOptions o;
  o.ransac.epsilon = 0.01;
  ASSERT_EQ(o.classes.keep, (std::vector<std::uint8_t>{6}));  // the default
  const auto out = fit_point_cloud(c.points, classes, o);
  ASSERT_TRUE(out.ok()) << out.error().message;
  EXPECT_EQ(out->other_class_points, 5000);
  EXPECT_EQ(out->per_type[static_cast<int>(PrimitiveType::Sphere)], 0);
  EXPECT_EQ(out->per_type[static_cast<int>(PrimitiveType::Cylinder)], 1);
  EXPECT_EQ(out->per_type[static_cast<int>(PrimitiveType::Box)], 1);
}

TEST(FitSegment, PipelineOutputIsTheSameBytesForTheSameSeed) {
  const Cloud c = small_scene();
  FitPipelineOptions o;
  o.ransac.epsilon = 0.01;
  o.ransac.seed = 42;
  auto text = [&] {
    const auto out = fit_point_cloud(c.points, {}, o);
    EXPECT_TRUE(out.ok());
    Scene s;
    s.name = "determinism";
    s.primitives = out->primitives;
    return scene_to_json(s);
  };
  const std::string a = text();
  EXPECT_EQ(a, text());
  EXPECT_NE(a.find("\"quality\""), std::string::npos);
}

TEST(FitSegment, PipelineWithRegionGrowingKeepsEveryClusterPointAndIsDeterministic) {
  const Cloud c = small_scene();
  FitPipelineOptions o = small_scene_options();
  const auto whole = fit_point_cloud(c.points, {}, o);
  ASSERT_TRUE(whole.ok()) << whole.error().message;
  o.regions.enabled = true;
  auto run = [&] {
    const auto out = fit_point_cloud(c.points, {}, o);
    EXPECT_TRUE(out.ok());
    Scene s;
    s.name = "regions";
    s.primitives = out->primitives;
    return std::make_pair(*out, scene_to_json(s));
  };
  const auto [split, text] = run();
  EXPECT_GT(split.regions, whole->regions);  // the beam's faces, at least, come apart
  long long in_regions = 0;
  for (const auto& r : split.region_stats) in_regions += r.points;
  EXPECT_EQ(in_regions, split.fitted_points - split.small_cluster_points);
  EXPECT_EQ(split.per_type[static_cast<int>(PrimitiveType::Sphere)], 1);
  EXPECT_EQ(split.per_type[static_cast<int>(PrimitiveType::Cylinder)], 1);
  EXPECT_EQ(text, run().second);
  o.regions.smoothness_deg = 0.0;
  const auto bad = fit_point_cloud(c.points, {}, o);
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.error().message.find("regions.smoothness_deg"), std::string::npos);
}

TEST(FitSegment, PipelineOptionsAreChecked) {
  FitPipelineOptions o;
  o.normals.neighbours = 1;
  const std::vector<Vec3> p(10, Vec3::Zero());
  const auto out = fit_point_cloud(p, {}, o);
  ASSERT_FALSE(out.ok());
  EXPECT_NE(out.error().message.find("normals.neighbours"), std::string::npos);
  const auto empty = fit_point_cloud(std::vector<Vec3>{}, {}, FitPipelineOptions{});
  ASSERT_TRUE(empty.ok());
  EXPECT_TRUE(empty->primitives.empty());
}

// A classified building whose roof no plane explains (a bumpy 10 × 8 m roof, ±0.8 m) is not
// left out: it becomes an LoD1.2 block, its outline extruded from the terrain to the 70th
// percentile of its heights. The same points unclassified (a tree could look like this) make
// no block.
TEST(FitSegment, BuildingPointsNoSurfaceExplainsBecomeAnLod12Block) {
  Cloud c =
      testing::rectangle_cloud(Vec3(-15, -15, 0), Vec3(40, 0, 0), Vec3(0, 40, 0), 0.3, 0.01, 31);
  const std::size_t ground = c.points.size();
  std::vector<double> heights;
  for (double x = 0.0; x < 10.0; x += 0.3) {
    for (double y = 0.0; y < 8.0; y += 0.3) {
      const double z = 7.0 + 0.8 * std::sin(1.7 * x) * std::cos(1.3 * y);
      c.points.emplace_back(x, y, z);
      c.normals.emplace_back(0, 0, 1);
      heights.push_back(z);
    }
  }
  std::sort(heights.begin(), heights.end());
  const double p70 =
      heights[static_cast<std::size_t>(0.7 * static_cast<double>(heights.size() - 1))];
  std::vector<std::uint8_t> classes(c.points.size(), 6);
  std::fill(classes.begin(), classes.begin() + static_cast<std::ptrdiff_t>(ground), 2);
  FitPipelineOptions o;
  o.outliers.enabled = false;
  const auto out = fit_point_cloud(c.points, classes, o);
  ASSERT_TRUE(out.ok()) << out.error().message;
  const geo::ScenePrimitive* block = nullptr;
  for (const auto& p : out->primitives) {
    if (p.spec.type == PrimitiveType::Extrusion && p.spec.clips.empty()) block = &p;
  }
  std::string found;
  for (const auto& p : out->primitives)
    found += std::string(kernel::primitive_type_name(p.spec.type)) + " ";
  for (const auto& r : out->rejected) found += "| " + r.what + ": " + r.reason + " ";
  ASSERT_NE(block, nullptr) << found;
  const auto solid = kernel::build_primitive(block->spec);
  ASSERT_TRUE(solid.ok());
  const kernel::BoundingBox box = kernel::bounding_box(solid.value());
  EXPECT_NEAR(box.max.z(), p70, 0.05);
  EXPECT_NEAR(box.min.z(), 0.0, 0.1);
  EXPECT_NEAR(box.min.x(), 0.0, 0.5);
  EXPECT_NEAR(box.max.x(), 10.0, 0.5);
  EXPECT_NEAR(box.max.y(), 8.0, 0.5);
  // Unclassified: the same cloud makes no block (ground from the morphological filter).
  const auto bare = fit_point_cloud(c.points, {}, o);
  ASSERT_TRUE(bare.ok());
  for (const auto& p : bare->primitives) {
    // A block would be an unclipped extrusion from the terrain (z = 0) to the 70th percentile.
    EXPECT_FALSE(p.spec.type == PrimitiveType::Extrusion && p.spec.clips.empty() &&
                 std::abs(p.spec.height - p70) < 0.05)
        << "a block from unclassified points";
  }
}

}  // namespace
}  // namespace csgtile::fit

namespace csgtile::fit {
namespace {

// The segmentation as an output (issue #24 item 4): one label per input point, in input
// order; ground points have none; every labelled point lies on its surface, and each surface's
// labelled points are its inliers; with voxel downsampling every fitted input point still gets
// the surface of its voxel's point.
TEST(FitSegment, SegmentsLabelEveryInputPointWithItsSurface) {
  const testing::Cloud c = small_scene();
  FitPipelineOptions o = small_scene_options();
  o.keep_segments = true;
  // The ground plane (the first cloud of small_scene) classified as such: ground by class.
  const std::size_t ground = 10 * 10 * 100;
  std::vector<std::uint8_t> classes(c.points.size(), 1);
  std::fill(classes.begin(), classes.begin() + static_cast<std::ptrdiff_t>(ground), 2);
  const auto out = fit_point_cloud(c.points, classes, o);
  ASSERT_TRUE(out.ok()) << out.error().message;
  ASSERT_EQ(out->point_segment.size(), c.points.size());
  ASSERT_GE(out->segments.size(), 3U);
  std::vector<long long> count(out->segments.size(), 0);
  for (std::size_t i = 0; i < c.points.size(); ++i) {
    const int s = out->point_segment[i];
    ASSERT_GE(s, -1);
    ASSERT_LT(s, static_cast<int>(out->segments.size()));
    if (i < ground) {
      EXPECT_EQ(s, -1) << "ground point " << i;
    }
    if (s < 0) continue;
    ++count[static_cast<std::size_t>(s)];
    EXPECT_LE(
        std::abs(surface_distance(out->segments[static_cast<std::size_t>(s)].surface, c.points[i])),
        0.01 + 1e-9);
  }
  for (std::size_t s = 0; s < count.size(); ++s) EXPECT_EQ(count[s], out->segments[s].inliers);
  // The sphere's points (the last 5 000) are one sphere surface.
  const int sphere = out->point_segment[c.points.size() - 1];
  ASSERT_GE(sphere, 0);
  EXPECT_EQ(out->segments[static_cast<std::size_t>(sphere)].surface.type, ShapeType::Sphere);
  long long on_sphere = 0;
  for (std::size_t i = c.points.size() - 5000; i < c.points.size(); ++i)
    on_sphere += out->point_segment[i] == sphere ? 1 : 0;
  EXPECT_GT(on_sphere, 4500);
  // Without keep_segments nothing is kept.
  o.keep_segments = false;
  const auto plain = fit_point_cloud(c.points, classes, o);
  ASSERT_TRUE(plain.ok());
  EXPECT_TRUE(plain->point_segment.empty());
  EXPECT_TRUE(plain->segments.empty());
  // Downsampled: the labels still cover the input, and the sphere is still labelled.
  o.keep_segments = true;
  o.voxel.size = 0.03;
  const auto coarse = fit_point_cloud(c.points, classes, o);
  ASSERT_TRUE(coarse.ok());
  ASSERT_EQ(coarse->point_segment.size(), c.points.size());
  const int s2 = coarse->point_segment[c.points.size() - 1];
  ASSERT_GE(s2, 0);
  EXPECT_EQ(coarse->segments[static_cast<std::size_t>(s2)].surface.type, ShapeType::Sphere);
  for (std::size_t i = 0; i < ground; ++i) {
    EXPECT_EQ(coarse->point_segment[i], -1);
  }
}

// Scale-aware options (issue #24 item 1): with epsilon, min_points and max_radius left to the
// cloud (0), the same object in metres and in millimetres gives the same shapes — the same
// types and, point for point, nearly the same labels — with no setting changed.
TEST(FitSegment, DerivedOptionsGiveTheSameShapesInAnyUnit) {
  testing::Cloud c =
      testing::rectangle_cloud(Vec3::Zero(), Vec3(2, 0, 0), Vec3(0, 1, 0), 0.03, 0.0, 31);
  c.append(testing::rectangle_cloud(Vec3::Zero(), Vec3(2, 0, 0), Vec3(0, 0, 1), 0.03, 0.0, 32));
  c.append(testing::cylinder_cloud(Vec3(1, 0.5, 0), Vec3::UnitZ(), 0.2, 0.8, 0.0,
                                   2.0 * std::numbers::pi, 1500, 0.0, 33));
  FitPipelineOptions o;
  o.ground.enabled = false;
  o.outliers.enabled = false;
  o.ransac.epsilon = 0.0;
  o.ransac.min_points = 0;
  o.ransac.max_radius = 0.0;
  o.keep_segments = true;
  const auto metres = fit_point_cloud(c.points, {}, o);
  ASSERT_TRUE(metres.ok()) << metres.error().message;
  std::vector<Vec3> mm = c.points;
  for (auto& p : mm) p *= 1000.0;
  const auto millimetres = fit_point_cloud(mm, {}, o);
  ASSERT_TRUE(millimetres.ok()) << millimetres.error().message;
  ASSERT_GE(metres->segments.size(), 3U);
  ASSERT_EQ(metres->segments.size(), millimetres->segments.size());
  for (std::size_t s = 0; s < metres->segments.size(); ++s) {
    EXPECT_EQ(metres->segments[s].surface.type, millimetres->segments[s].surface.type);
  }
  std::size_t same = 0;
  for (std::size_t i = 0; i < c.points.size(); ++i)
    same += metres->point_segment[i] == millimetres->point_segment[i] ? 1 : 0;
  EXPECT_GE(static_cast<double>(same), 0.99 * static_cast<double>(c.points.size()));
  // The derived inlier distance scales with the cloud.
  ASSERT_FALSE(metres->region_stats.empty());
  EXPECT_NEAR(millimetres->region_stats[0].spacing, 1000.0 * metres->region_stats[0].spacing,
              1e-6 * millimetres->region_stats[0].spacing);
  // The cylinder is found as one.
  const int cyl = metres->point_segment[c.points.size() - 1];
  ASSERT_GE(cyl, 0);
  EXPECT_EQ(metres->segments[static_cast<std::size_t>(cyl)].surface.type, ShapeType::Cylinder);
}

// A tile among neighbours (TileShare): the points of x > 1 are a neighbour's. A cluster the
// share gives to a neighbour is not fitted (its points counted as left to it), one kept whole
// is fitted with the neighbour's points, one kept to its own points loses the neighbour's;
// the structure points are this tile's own only.
struct Shared {
  std::vector<std::uint8_t> foreign;
  TileShare share;
};
Shared split_at_x1(const Cloud& c, ShareKind beam_and_column) {
  Shared s;
  for (const Vec3& p : c.points) s.foreign.push_back(p.x() > 1.0 ? 1 : 0);
  s.share.foreign = s.foreign;
  // The column and beam are the cluster whose box reaches past x = 1.
  s.share.clusters = [beam_and_column](const kernel::Vec2&, const kernel::Vec2& hi, double) {
    return hi.x() > 1.0 ? beam_and_column : ShareKind::whole;
  };
  return s;
}
FitPipelineOptions scene_options() {
  FitPipelineOptions o = small_scene_options();
  o.keep_structure_points = true;
  return o;
}

TEST(FitSegment, TileShareLeavesANeighboursClusterToIt) {
  const Cloud c = small_scene();
  Shared s = split_at_x1(c, ShareKind::none);
  const auto out = fit_point_cloud(c.points, {}, scene_options(), {}, {}, &s.share);
  ASSERT_TRUE(out.ok()) << out.error().message;
  EXPECT_EQ(out->per_type[static_cast<int>(PrimitiveType::Cylinder)], 0);
  EXPECT_EQ(out->per_type[static_cast<int>(PrimitiveType::Box)], 0);
  EXPECT_EQ(out->per_type[static_cast<int>(PrimitiveType::Sphere)], 1);
  EXPECT_EQ(out->clusters_left_to_neighbours, 1);
  EXPECT_GT(out->points_left_to_neighbours, 6000);  // the column's and the beam's
  EXPECT_EQ(out->neighbour_points, std::count(s.foreign.begin(), s.foreign.end(), std::uint8_t{1}));
  for (const Vec3& p : out->structure_points) EXPECT_LE(p.x(), 1.0);
  // The column's own points are still this tile's structure points (it publishes its own).
  EXPECT_TRUE(std::any_of(out->structure_points.begin(), out->structure_points.end(),
                          [](const Vec3& p) { return p.z() > 1.0 && p.norm() < 2.0; }));
}

TEST(FitSegment, TileShareKeepsAWholeClusterWithTheNeighboursPoints) {
  const Cloud c = small_scene();
  Shared s = split_at_x1(c, ShareKind::whole);
  const auto whole = fit_point_cloud(c.points, {}, scene_options(), {}, {}, &s.share);
  ASSERT_TRUE(whole.ok()) << whole.error().message;
  EXPECT_EQ(whole->per_type[static_cast<int>(PrimitiveType::Cylinder)], 1);
  EXPECT_EQ(whole->per_type[static_cast<int>(PrimitiveType::Box)], 1);
  EXPECT_EQ(whole->clusters_left_to_neighbours, 0);
  EXPECT_EQ(whole->points_left_to_neighbours, 0);
  // The beam reaches x = 2.7 (its far part from the neighbour's points).
  double beam_end = 0.0;
  for (const auto& p : whole->primitives) {
    if (p.spec.type != PrimitiveType::Box) continue;
    auto solid = kernel::build_primitive(p.spec, 1e-7);
    ASSERT_TRUE(solid.ok());
    beam_end = kernel::bounding_box(solid.value()).max.x();
  }
  EXPECT_GT(beam_end, 2.5);

  // Kept to its own points, the beam stops where this tile's points do.
  s = split_at_x1(c, ShareKind::own_points);
  const auto own = fit_point_cloud(c.points, {}, scene_options(), {}, {}, &s.share);
  ASSERT_TRUE(own.ok()) << own.error().message;
  EXPECT_EQ(own->clusters_split_with_neighbours, 1);
  EXPECT_GT(own->points_left_to_neighbours, 0);
  for (const auto& p : own->primitives) {
    auto solid = kernel::build_primitive(p.spec, 1e-7);
    ASSERT_TRUE(solid.ok());
    EXPECT_LT(kernel::bounding_box(solid.value()).max.x(), 1.2) << p.id;
  }
}

// A footprint whose building a neighbour makes: its points are left out and it is no
// "footprint without building"; kept whole, its primitives carry its id. Spans of the wrong
// size are an error naming the share.
TEST(FitSegment, TileShareOfFootprints) {
  const Cloud c = small_scene();
  geo::Footprint sphere;
  sphere.id = "sphere-house";
  sphere.polygons.push_back({{{-4.5, 0.5}, {-1.5, 0.5}, {-1.5, 3.5}, {-4.5, 3.5}}, {}});
  const std::vector<geo::Footprint> footprints{sphere};
  std::vector<std::uint8_t> foreign(c.points.size(), 0);
  std::vector<ShareKind> kinds{ShareKind::none};
  TileShare share;
  share.foreign = foreign;
  share.footprints = kinds;
  const auto left = fit_point_cloud(c.points, {}, scene_options(), footprints, {}, &share);
  ASSERT_TRUE(left.ok()) << left.error().message;
  EXPECT_EQ(left->footprint_regions, 0);
  EXPECT_TRUE(left->footprints_without_building.empty());
  EXPECT_GE(left->points_left_to_neighbours, 4000);
  for (const auto& p : left->primitives) EXPECT_TRUE(p.building.empty()) << p.id;

  kinds = {ShareKind::whole};
  const auto kept = fit_point_cloud(c.points, {}, scene_options(), footprints, {}, &share);
  ASSERT_TRUE(kept.ok()) << kept.error().message;
  EXPECT_EQ(kept->footprint_regions, 1);
  EXPECT_TRUE(std::any_of(kept->primitives.begin(), kept->primitives.end(),
                          [](const auto& p) { return p.building == "sphere-house"; }));

  kinds.clear();
  share.footprints = kinds;
  const auto bad = fit_point_cloud(c.points, {}, scene_options(), footprints, {}, &share);
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.error().message.find("tile share"), std::string::npos);
}

// The regions are fitted in parallel (FitPipelineOptions::threads) and gathered in order: the
// same scene JSON, segments and statistics on 1, 2 and 8 threads (small_scene's column and
// beam are one region, the sphere another).
TEST(FitSegment, TheSameFitOnEveryThreadCount) {
  const Cloud c = small_scene();
  FitPipelineOptions o = small_scene_options();
  o.keep_segments = true;
  std::string first;
  std::vector<std::int32_t> first_segments;
  for (const int threads : {1, 2, 8}) {
    o.threads = threads;
    const auto out = fit_point_cloud(c.points, {}, o);
    ASSERT_TRUE(out.ok()) << out.error().message;
    EXPECT_GE(out->region_stats.size(), 2u);
    Scene s;
    s.primitives = out->primitives;
    std::string text = scene_to_json(s) + " candidates " + std::to_string(out->candidates) +
                       " assigned " + std::to_string(out->assigned_points) + " rejected " +
                       std::to_string(out->rejected.size());
    for (const auto& r : out->region_stats)
      text += " " + std::to_string(r.points) + "/" + std::to_string(r.shapes);
    if (threads == 1) {
      first = text;
      first_segments = out->point_segment;
      EXPECT_FALSE(out->primitives.empty());
    } else {
      EXPECT_EQ(text, first) << threads << " threads";
      EXPECT_EQ(out->point_segment, first_segments) << threads << " threads";
    }
  }
}

}  // namespace
}  // namespace csgtile::fit
