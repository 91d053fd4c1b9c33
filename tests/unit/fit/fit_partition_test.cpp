// The roof partition of buildings seen from the air (issue #18 item 3): a labelled grid's
// parts become polygons that share their boundaries exactly (partition.cpp), and a
// building's outline is partitioned among its roof planes, each part the extrusion of its
// polygon from the terrain clipped under its plane (roof_partition.cpp): a gable house, a
// row of houses with different ridge heights, a hip roof over an L, a flat roof with a
// parapet.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>

#include "csgtile/fit/fit.h"
#include "csgtile/kernel/mass_properties.h"
#include "fit_clouds.h"
#include "fit_internal.h"
#include "footprint_clip.h"
#include "partition.h"
#include "plane2d.h"
#include "proposal_input.h"

namespace csgtile::fit {
namespace {

using detail::LabelGrid;
using detail::PartPolygon;
using kernel::Vec2;
using kernel::Vec3;
using testing::Cloud;

LabelGrid grid_of(const std::vector<std::string>& rows) {
  // rows[0] is the top row (largest j); '.' outside, digits labels.
  LabelGrid g;
  g.ny = static_cast<int>(rows.size());
  g.nx = static_cast<int>(rows[0].size());
  g.label.assign(static_cast<std::size_t>(g.nx * g.ny), -1);
  for (int j = 0; j < g.ny; ++j) {
    const std::string& r = rows[static_cast<std::size_t>(g.ny - 1 - j)];
    for (int i = 0; i < g.nx; ++i) {
      if (r[static_cast<std::size_t>(i)] != '.')
        g.cell(i, j) = r[static_cast<std::size_t>(i)] - '0';
    }
  }
  return g;
}

double area_of(const PartPolygon& p) { return detail::polygon_area(p.outer, p.holes); }

// Every cell centre lies in the polygon of its own part and in no other.
void expect_tiles(const LabelGrid& g, const std::vector<PartPolygon>& parts) {
  for (int j = 0; j < g.ny; ++j) {
    for (int i = 0; i < g.nx; ++i) {
      const Vec2 c(i + 0.5, j + 0.5);
      int inside = 0, own = -2;
      for (std::size_t k = 0; k < parts.size(); ++k) {
        if (detail::inside_polygon(c, parts[k].outer, parts[k].holes)) {
          ++inside;
          own = parts[k].label;
        }
      }
      if (g.at(i, j) < 0) {
        EXPECT_EQ(inside, 0) << "outside cell " << i << "," << j << " covered";
      } else {
        EXPECT_EQ(inside, 1) << "cell " << i << "," << j;
        EXPECT_EQ(own, g.at(i, j)) << "cell " << i << "," << j;
      }
    }
  }
}

TEST(FitPartition, TwoLabelsSideBySideShareOneWall) {
  const LabelGrid g = grid_of({"......", ".0011.", ".0011.", ".0011.", "......"});
  const auto parts = detail::partition_polygons(g, 0.9);
  ASSERT_EQ(parts.size(), 2U);
  EXPECT_DOUBLE_EQ(area_of(parts[0]), 6.0);
  EXPECT_DOUBLE_EQ(area_of(parts[1]), 6.0);
  EXPECT_EQ(parts[0].outer.size(), 4U);  // rectangles: collinear cell corners removed
  EXPECT_EQ(parts[1].outer.size(), 4U);
  EXPECT_GT(detail::ring_area(parts[0].outer), 0.0);  // counter-clockwise
  expect_tiles(g, parts);
}

TEST(FitPartition, AStaircaseBoundaryIsOneStraightLineForBothSides) {
  // A diagonal between labels 0 and 1 drawn in cells: simplified once, used by both.
  const LabelGrid g =
      grid_of({"..........", ".00000001.", ".00000011.", ".00000111.", ".00001111.", ".00011111.",
               ".00111111.", ".01111111.", ".11111111.", ".........."});
  const auto parts = detail::partition_polygons(g, 0.9);
  ASSERT_EQ(parts.size(), 2U);
  EXPECT_LT(parts[0].outer.size(), 8U);
  EXPECT_LT(parts[1].outer.size(), 8U);
  // The areas add up to the outline's: no gap and no overlap between the two.
  EXPECT_NEAR(area_of(parts[0]) + area_of(parts[1]), 64.0, 1e-9);
  // The vertices of one that lie inside the outline are vertices of the other.
  for (const auto& p : parts[0].outer) {
    if (p.x() <= 1.0 || p.y() <= 1.0 || p.x() >= 9.0 || p.y() >= 9.0) continue;
    const bool shared =
        std::find(parts[1].outer.begin(), parts[1].outer.end(), p) != parts[1].outer.end();
    EXPECT_TRUE(shared) << p.transpose();
  }
}

TEST(FitPartition, APartInsideAnotherIsItsHole) {
  const LabelGrid g = grid_of({".......", ".00000.", ".01110.", ".01110.", ".00000.", "......."});
  const auto parts = detail::partition_polygons(g, 0.9);
  ASSERT_EQ(parts.size(), 2U);
  ASSERT_EQ(parts[0].holes.size(), 1U);
  EXPECT_DOUBLE_EQ(area_of(parts[0]), 20.0 - 6.0);
  EXPECT_DOUBLE_EQ(area_of(parts[1]), 6.0);
  expect_tiles(g, parts);
}

TEST(FitPartition, PinchesAreJoined) {
  // Label 0 touching itself at a corner, and labels 1 and 2 meeting at a corner only.
  LabelGrid g = grid_of({".....", ".00..", ".000.", "..00.", ".....", ".1...", "..2..", "....."});
  EXPECT_GT(detail::unpinch(g), 0);
  EXPECT_EQ(detail::unpinch(g), 0);
  for (int j = -1; j < g.ny; ++j) {
    for (int i = -1; i < g.nx; ++i) {
      const int p = g.at(i, j), q = g.at(i + 1, j), r = g.at(i, j + 1), s = g.at(i + 1, j + 1);
      EXPECT_FALSE(p == s && q != p && r != p) << i << "," << j;
      EXPECT_FALSE(q == r && p != q && s != q) << i << "," << j;
      EXPECT_FALSE(p != q && p != r && p != s && q != r && q != s && r != s) << i << "," << j;
    }
  }
  // Without simplification the polygons are exactly the cells of each part.
  const auto parts = detail::partition_polygons(g, 0.0);
  expect_tiles(g, parts);
}

// Three parts clipped to a footprint: a large one whose straight wall runs along two small
// ones, and the small ones' shared corner on that wall. The vertex snap moves the corner 7 mm
// onto a vertex seen before (here: given), off the large part's wall; share_vertices puts it
// into that wall, so that all three share their boundaries again (a T-junction 7 mm off the
// wall made the real Delft parts' fuse fail). Vertices farther than the distance stay out,
// and a vertex already in a ring is not inserted twice.
TEST(FitPartition, VerticesTheSnapMovedAreSharedByTheWallsTheyLeft) {
  detail::VertexSnap snap(0.05);
  detail::FramePolygon seen;  // the vertex the corner snaps to: 7 mm off the wall x = 4
  seen.outer = {{4.007, 2.0}, {6.0, 2.0}, {6.0, 3.0}};
  ASSERT_TRUE(snap.snap(seen));
  std::vector<std::vector<detail::FramePolygon>> parts(3);
  parts[0].push_back(*snap.snap({{{0, 0}, {4, 0}, {4, 4}, {0, 4}}, {}}));  // wall x = 4
  parts[1].push_back(*snap.snap({{{4, 0}, {6, 0}, {6, 2}, {4, 2}}, {}}));  // corner (4, 2)
  parts[2].push_back(*snap.snap({{{4, 2}, {6, 2}, {6, 4}, {4, 4}}, {}}));
  ASSERT_EQ(parts[1][0].outer[3], Vec2(4.007, 2.0));  // moved by the snap
  // A vertex 0.2 m off the wall, beyond the distance: not shared.
  parts.push_back({{{{5.0, 5.0}, {4.2, 6.0}, {5.0, 7.0}}, {}}});
  detail::share_vertices(parts, 0.05);
  const std::vector<Vec2> wall = {{0, 0}, {4, 0}, {4.007, 2.0}, {4, 4}, {0, 4}};
  EXPECT_EQ(parts[0][0].outer, wall);
  EXPECT_EQ(parts[1][0].outer.size(), 4U);  // its own corner is not inserted again
  EXPECT_EQ(parts[2][0].outer.size(), 4U);
  EXPECT_EQ(parts[3][0].outer.size(), 3U);
  detail::share_vertices(parts, 0.05);  // a second call changes nothing
  EXPECT_EQ(parts[0][0].outer, wall);
}

// ---- Roof partition of buildings ----

// Flat terrain at z = 0 over [-20, 60]², seen from the air around a building over
// [x0, x1] × [y0, y1]: no ground under its roof.
GroundGrid ground_around(double x0, double y0, double x1, double y1) {
  GroundGrid g = testing::flat_ground();
  for (int j = 0; j < g.ny; ++j) {
    for (int i = 0; i < g.nx; ++i) {
      const double x = g.x0 + (i + 0.5) * g.cell, y = g.y0 + (j + 0.5) * g.cell;
      if (x > x0 && x < x1 && y > y0 && y < y1) {
        g.z[static_cast<std::size_t>(j * g.nx + i)] = NAN;
        g.mean[static_cast<std::size_t>(j * g.nx + i)] = NAN;
      }
    }
  }
  return g;
}

Cloud roof(const Vec3& corner, const Vec3& e1, const Vec3& e2, std::uint64_t seed) {
  return testing::rectangle_cloud(corner, e1, e2, std::sqrt(0.1), 0.03, seed);  // AHN-like
}

struct Partitioned {
  std::vector<detail::Proposal> parts;
  std::vector<Rejection> rejected;
  std::vector<kernel::Shape> solids;
};

Partitioned partition(const Cloud& c, const GroundGrid& ground) {
  RansacOptions o;
  o.epsilon = 0.1;
  o.min_points = 40;
  o.seed = 5;
  auto shapes = detect_shapes(c.points, c.normals, o);
  EXPECT_TRUE(shapes.ok());
  PrimitiveOptions options;
  options.ground = &ground;
  options.roof_partition = true;
  const testing::FreshProposalInput fresh(c, shapes.value(), options, o);
  Partitioned out;
  out.parts = detail::propose_roof_partition(fresh.in, out.rejected);
  for (const auto& p : out.parts) {
    auto solid = kernel::build_primitive(p.spec);
    EXPECT_TRUE(solid.ok()) << p.what << ": " << solid.error().message;
    if (solid.ok()) out.solids.push_back(std::move(solid.value()));
  }
  return out;
}

// Height of the model's top at (x, y): the highest point of any part over it, by bisection
// on containment (parts are vertical extrusions clipped by a plane: one interval in z).
double top_at(const Partitioned& p, double x, double y) {
  double best = -INFINITY;
  for (std::size_t k = 0; k < p.solids.size(); ++k) {
    const kernel::BoundingBox b = kernel::bounding_box(p.solids[k]);
    if (x < b.min.x() || x > b.max.x() || y < b.min.y() || y > b.max.y()) continue;
    const auto& spec = p.parts[k].spec;
    const Vec3 local = spec.placement.inverse().apply_point(Vec3(x, y, 0.0));
    if (!detail::inside_polygon(Vec2(local.x(), local.y()), spec.profile, spec.holes)) continue;
    double top = b.max.z();
    for (const auto& c : spec.clips) {
      // Local plane c.xyz · q <= c.w along the vertical through (x, y).
      const Vec3 base = spec.placement.inverse().apply_point(Vec3(x, y, 0.0));
      const Vec3 up = spec.placement.rotation().transpose() * Vec3::UnitZ();
      const double t =
          (c.w() - Vec3(c.x(), c.y(), c.z()).dot(base)) / Vec3(c.x(), c.y(), c.z()).dot(up);
      top = std::min(top, t);
    }
    best = std::max(best, top);
  }
  return best;
}

// The houses the partition's parts belong to (Proposal::house), distinct, ascending.
std::vector<int> houses_of(const Partitioned& p) {
  std::vector<int> out;
  for (const auto& part : p.parts) out.push_back(part.house);
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

TEST(FitRoofPartition, GableHouseIsTwoPartsMeetingAtTheRidge) {
  // 12 × 8 m, eaves at 6 m along y = 0 and y = 8, ridge at 9 m along y = 4.
  const GroundGrid ground = ground_around(0, 0, 12, 8);
  Cloud c = roof(Vec3(0, 0, 6), Vec3(12, 0, 0), Vec3(0, 4, 3), 1);
  c.append(roof(Vec3(0, 4, 9), Vec3(12, 0, 0), Vec3(0, 4, -3), 2));
  const auto p = partition(c, ground);
  ASSERT_EQ(p.parts.size(), 2U);
  for (const auto& part : p.parts) EXPECT_EQ(part.spec.clips.size(), 1U) << part.what;
  EXPECT_EQ(houses_of(p), std::vector<int>{0});  // its slopes meet at the ridge: one house
  double volume = 0.0;
  for (const auto& s : p.solids) volume += kernel::mass_properties(s).volume;
  const double expected = 12.0 * 8.0 * 6.0 + 0.5 * 12.0 * 8.0 * 3.0;  // 720 m³
  EXPECT_NEAR(volume, expected, 0.05 * expected);
  // The roof's height along a cross-section, away from the outline's edges.
  for (double y = 0.5; y <= 7.5; y += 0.5) {
    const double truth = 9.0 - 0.75 * std::abs(y - 4.0);
    EXPECT_NEAR(top_at(p, 6.0, y), truth, 0.3) << "y " << y;
  }
}

// The box around every part of a partition.
kernel::BoundingBox model_extent(const Partitioned& p) {
  kernel::BoundingBox all;
  for (const auto& s : p.solids) all.add(kernel::bounding_box(s));
  return all;
}

// The four facades of a 12 × 8 m building from 0.5 m to 5 m, `depth` outside its walls.
void add_facades(Cloud& c, double depth, std::uint64_t seed) {
  c.append(roof(Vec3(0, -depth, 0.5), Vec3(12, 0, 0), Vec3(0, 0, 4.5), seed));
  c.append(roof(Vec3(12 + depth, 0, 0.5), Vec3(0, 8, 0), Vec3(0, 0, 4.5), seed + 1));
  c.append(roof(Vec3(12, 8 + depth, 0.5), Vec3(-12, 0, 0), Vec3(0, 0, 4.5), seed + 2));
  c.append(roof(Vec3(-depth, 8, 0.5), Vec3(0, -8, 0), Vec3(0, 0, 4.5), seed + 3));
}

void expect_extent(const Partitioned& p, double x0, double y0, double x1, double y1,
                   double tolerance) {
  ASSERT_FALSE(p.parts.empty());
  const kernel::BoundingBox box = model_extent(p);
  EXPECT_NEAR(box.min.x(), x0, tolerance);
  EXPECT_NEAR(box.max.x(), x1, tolerance);
  EXPECT_NEAR(box.min.y(), y0, tolerance);
  EXPECT_NEAR(box.max.y(), y1, tolerance);
}

// A flat roof (12 × 8 m at 6 m) whose eaves reach 0.6 m past its walls. Seen from the air
// alone, the outline ends where the roof does; where the scan also sees the facades (points
// down the walls, as AHN4's are), the walls stand on them.
TEST(FitRoofPartition, WallsStandOnTheFacadesWhereTheScanSeesThemElseAtTheEaves) {
  const GroundGrid ground = ground_around(0, 0, 12, 8);
  const Cloud eaves = roof(Vec3(-0.6, -0.6, 6), Vec3(13.2, 0, 0), Vec3(0, 9.2, 0), 1);
  expect_extent(partition(eaves, ground), -0.6, -0.6, 12.6, 8.6, 0.3);
  Cloud seen = eaves;
  add_facades(seen, 0.0, 2);
  expect_extent(partition(seen, ground), 0.0, 0.0, 12.0, 8.0, 0.1);
}

// The same building, its facades in relief as real ones are (window reveals 0.35 m deep,
// pilasters 0.35 m proud: the facade points spread 0.29 m RMS across the wall): the walls
// still stand on the facades' middle, not at the eaves.
TEST(FitRoofPartition, WallsStandOnFacadesInRelief) {
  const GroundGrid ground = ground_around(0, 0, 12, 8);
  Cloud c = roof(Vec3(-0.6, -0.6, 6), Vec3(13.2, 0, 0), Vec3(0, 9.2, 0), 1);
  add_facades(c, -0.35, 10);  // + outwards
  add_facades(c, 0.0, 14);
  add_facades(c, 0.35, 18);
  expect_extent(partition(c, ground), 0.0, 0.0, 12.0, 8.0, 0.15);
}

// Near-horizontal roof planes are made horizontal only where a level roof still explains
// their points: a 20 m roof sloping 3° (1 m of rise, within the 5° angle tolerance) keeps its
// slope; one sloping 0.2° (7 cm) is made level.
TEST(FitRoofPartition, AGentleSlopeKeepsItsRiseANearlyFlatRoofIsLevel) {
  const GroundGrid ground = ground_around(0, 0, 20, 10);
  for (const double degrees : {3.0, 0.2}) {
    const double rise = 20.0 * std::tan(degrees * std::numbers::pi / 180.0);
    const Cloud c = roof(Vec3(0, 0, 6), Vec3(20, 0, rise), Vec3(0, 10, 0), 41);
    const auto p = partition(c, ground);
    ASSERT_FALSE(p.parts.empty()) << degrees;
    const double low = top_at(p, 1.0, 5.0), high = top_at(p, 19.0, 5.0);
    if (degrees > 1.0) {
      EXPECT_NEAR(low, 6.0 + 0.05 * rise, 0.1);
      EXPECT_NEAR(high, 6.0 + 0.95 * rise, 0.1);
    } else {
      EXPECT_NEAR(high, low, 1e-9);
      EXPECT_NEAR(low, 6.0 + 0.5 * rise, 0.05);
    }
  }
}

// A roof no plane explains (a green roof: heights spread over 0.4 m, normals scattered) in
// two levels 0.8 m apart, the higher over x > 6. The cells no plane takes are split into
// pieces where their heights step by more than the largest residual the labelling accepts
// (2 tau: 0.5 m here), so each level is its own flat piece at its own height; a 1 m step let
// one piece at the 70th percentile of both (10.8 m) cover the lower level too.
TEST(FitRoofPartition, RoofsNoPlaneExplainsKeepTheirHeightSteps) {
  const GroundGrid ground = ground_around(0, 0, 12, 8);
  testing::Draw d(71);
  Cloud c;
  const int count = static_cast<int>(12 * 8 / 0.1);
  for (int i = 0; i < count; ++i) {
    const double x = d.uniform(0, 12), y = d.uniform(0, 8);
    const double z = (x > 6 ? 10.8 : 10.0) + d.uniform(-0.2, 0.2);
    c.add(Vec3(x, y, z), Vec3(d.normal(), d.normal(), d.normal()).normalized(), 0.0, d);
  }
  const auto p = partition(c, ground);
  ASSERT_FALSE(p.parts.empty());
  for (double y = 1.0; y <= 7.0; y += 1.0) {
    EXPECT_NEAR(top_at(p, 2.5, y), 10.0, 0.2) << "y " << y;
    EXPECT_NEAR(top_at(p, 9.5, y), 10.8, 0.2) << "y " << y;
  }
}

TEST(FitRoofPartition, NoPartitionWhereTheGroundIsSeenUnderTheRoof) {
  // The gable above, over terrain seen everywhere (a canopy scanned from the ground, a frame
  // of beams): no partition, and the reason is named.
  const GroundGrid ground = ground_around(0, 0, 0, 0);
  Cloud c = roof(Vec3(0, 0, 6), Vec3(12, 0, 0), Vec3(0, 4, 3), 1);
  c.append(roof(Vec3(0, 4, 9), Vec3(12, 0, 0), Vec3(0, 4, -3), 2));
  const auto p = partition(c, ground);
  EXPECT_TRUE(p.parts.empty());
  bool named = false;
  for (const auto& r : p.rejected)
    named = named || r.reason.find("ground is seen") != std::string::npos;
  EXPECT_TRUE(named);
}

TEST(FitRoofPartition, RowOfHousesWithDifferentRidgesKeepsEachRidge) {
  // Three gables side by side along x (6 m each), ridges at 9, 11 and 10 m.
  const GroundGrid ground = ground_around(0, 0, 18, 10);
  Cloud c;
  const double ridge[3] = {9.0, 11.0, 10.0};
  for (int h = 0; h < 3; ++h) {
    const double x0 = 6.0 * h, rise = ridge[h] - 6.0;
    c.append(roof(Vec3(x0, 0, 6), Vec3(6, 0, 0), Vec3(0, 5, rise), 10 + h));
    c.append(roof(Vec3(x0, 5, ridge[h]), Vec3(6, 0, 0), Vec3(0, 5, -rise), 20 + h));
  }
  const auto p = partition(c, ground);
  EXPECT_EQ(p.parts.size(), 6U);
  // Each gable a step against its neighbour's: three houses (issue #18 item 2), each the two
  // slopes over its own 6 m.
  EXPECT_EQ(houses_of(p), (std::vector<int>{0, 1, 2}));
  for (const auto& part : p.parts) {
    const kernel::BoundingBox box =
        kernel::bounding_box(kernel::build_primitive(part.spec).value());
    const int h = static_cast<int>(std::floor(0.5 * (box.min.x() + box.max.x()) / 6.0));
    for (const auto& other : p.parts) {
      const kernel::BoundingBox b =
          kernel::bounding_box(kernel::build_primitive(other.spec).value());
      const int g = static_cast<int>(std::floor(0.5 * (b.min.x() + b.max.x()) / 6.0));
      EXPECT_EQ(part.house == other.house, h == g) << part.what << " / " << other.what;
    }
  }
  int within = 0, total = 0;
  for (int h = 0; h < 3; ++h) {
    for (double x = 6.0 * h + 0.75; x < 6.0 * h + 5.3; x += 0.5) {
      for (double y = 0.5; y <= 9.5; y += 0.5) {
        const double truth = ridge[h] - (ridge[h] - 6.0) * std::abs(y - 5.0) / 5.0;
        ++total;
        within += std::abs(top_at(p, x, y) - truth) <= 0.3 ? 1 : 0;
      }
    }
  }
  EXPECT_GE(within, 0.95 * total) << within << " of " << total;
}

TEST(FitRoofPartition, HipRoofOverAnLIsPartitionedAlongItsHipsAndValley) {
  // An L of two hipped wings (10 × 20 along y and 20 × 10 along x sharing the corner
  // square), eaves at 5 m, slopes of 0.6: the roof is the lowest of the planes rising from
  // the outline's edges, z = 5 + 0.6 · (distance to the nearest edge), capped by the ridges.
  GroundGrid ground = ground_around(0, 0, 20, 10);
  const GroundGrid upper = ground_around(0, 0, 10, 20);
  for (std::size_t k = 0; k < ground.z.size(); ++k) {
    if (std::isnan(upper.z[k])) ground.z[k] = ground.mean[k] = NAN;
  }
  auto truth = [](double x, double y) {
    auto wing = [](double px, double py, double x0, double x1, double y0, double y1) -> double {
      if (px < x0 || px > x1 || py < y0 || py > y1) return -INFINITY;
      return 5.0 + 0.6 * std::min({px - x0, x1 - px, py - y0, y1 - py});
    };
    return std::max(wing(x, y, 0, 10, 0, 20), wing(x, y, 0, 20, 0, 10));
  };
  Cloud c;
  // Points uniform over the square, on the truth with σ = 3 cm along the normal of its slope.
  testing::Draw d(99);
  for (int k = 0; k < 3000; ++k) {
    const double x = d.uniform(0.0, 20.0), y = d.uniform(0.0, 20.0), h = 1e-3;
    const double z = truth(x, y);
    if (!std::isfinite(z)) continue;
    const double gx = (truth(x + h, y) - truth(x - h, y)) / (2 * h);
    const double gy = (truth(x, y + h) - truth(x, y - h)) / (2 * h);
    c.add(Vec3(x, y, z), Vec3(-gx, -gy, 1.0).normalized(), 0.03, d);
  }
  const auto p = partition(c, ground);
  EXPECT_GE(p.parts.size(), 6U);
  EXPECT_EQ(houses_of(p), std::vector<int>{0});  // hips and valley: one roof, one house
  int within = 0, total = 0;
  for (double x = 0.25; x < 20.0; x += 0.5) {
    for (double y = 0.25; y < 20.0; y += 0.5) {
      const double z = truth(x, y);
      if (!std::isfinite(z) || std::min({x, y, 20.0 - x, 20.0 - y}) < 0.6) continue;
      ++total;
      within += std::abs(top_at(p, x, y) - z) <= 0.3 ? 1 : 0;
    }
  }
  EXPECT_GE(within, 0.9 * total) << within << " of " << total;
}

TEST(FitRoofPartition, AChimneyOnASlopeIsAPartTheSlopeIsNotCutAround) {
  // A shed roof (6 m at y = 0 rising to 9 m at y = 10) over 14 × 10 m with a 2 × 2 m
  // chimney standing to 10.5 m in its middle: the chimney is a part of its own, the slope's
  // part has no hole (the two overlap; the fuse joins them), and the top is right on both.
  const GroundGrid ground = ground_around(0, 0, 14, 10);
  Cloud c = roof(Vec3(0, 0, 6), Vec3(14, 0, 0), Vec3(0, 4, 1.2), 41);
  c.append(roof(Vec3(0, 4, 7.2), Vec3(6, 0, 0), Vec3(0, 2, 0.6), 42));
  c.append(roof(Vec3(8, 4, 7.2), Vec3(6, 0, 0), Vec3(0, 2, 0.6), 43));
  c.append(roof(Vec3(0, 6, 7.8), Vec3(14, 0, 0), Vec3(0, 4, 1.2), 44));
  c.append(
      testing::rectangle_cloud(Vec3(6, 4, 10.5), Vec3(2, 0, 0), Vec3(0, 2, 0), 0.15, 0.01, 45));
  const auto p = partition(c, ground);
  ASSERT_GE(p.parts.size(), 2U);
  for (const auto& part : p.parts) {
    if (!part.spec.clips.empty()) {
      EXPECT_TRUE(part.spec.holes.empty()) << part.what;
    }
  }
  EXPECT_NEAR(top_at(p, 7.0, 5.0), 10.5, 0.2);   // the chimney
  EXPECT_EQ(houses_of(p), std::vector<int>{0});  // of the house it stands on
  for (double x : {2.0, 12.0}) {
    for (double y : {2.0, 5.0, 8.0})
      EXPECT_NEAR(top_at(p, x, y), 6.0 + 0.3 * y, 0.3) << x << "," << y;
  }
}

TEST(FitRoofPartition, FlatRoofWithAParapetKeepsTheRoofLevel) {
  // A 16 × 12 m flat roof at 10 m inside a 0.4 m wide parapet at 11 m.
  const GroundGrid ground = ground_around(0, 0, 16, 12);
  Cloud c = roof(Vec3(0.4, 0.4, 10), Vec3(15.2, 0, 0), Vec3(0, 11.2, 0), 31);
  c.append(roof(Vec3(0, 0, 11), Vec3(16, 0, 0), Vec3(0, 0.4, 0), 32));
  c.append(roof(Vec3(0, 11.6, 11), Vec3(16, 0, 0), Vec3(0, 0.4, 0), 33));
  c.append(roof(Vec3(0, 0.4, 11), Vec3(0.4, 0, 0), Vec3(0, 11.2, 0), 34));
  c.append(roof(Vec3(15.6, 0.4, 11), Vec3(0.4, 0, 0), Vec3(0, 11.2, 0), 35));
  const auto p = partition(c, ground);
  ASSERT_FALSE(p.parts.empty());
  EXPECT_EQ(houses_of(p), std::vector<int>{0});  // the parapet is the roof's
  for (double x = 2.0; x <= 14.0; x += 1.0) {
    for (double y = 2.0; y <= 10.0; y += 1.0) EXPECT_NEAR(top_at(p, x, y), 10.0, 0.1);
  }
  double lowest = INFINITY;
  for (const auto& s : p.solids) lowest = std::min(lowest, kernel::bounding_box(s).min.z());
  EXPECT_NEAR(lowest, 0.0, 0.1);  // from the terrain
}

}  // namespace
}  // namespace csgtile::fit
