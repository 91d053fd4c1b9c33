// From detected shapes to scene primitives: a beam seen from three sides is one
// box with its size and placement, curved shapes are bounded by their inliers,
// every primitive is a valid kernel solid with its fit quality.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "csgtile/fit/fit.h"
#include "csgtile/fit/segment.h"
#include "csgtile/kernel/check.h"
#include "fit_clouds.h"

namespace csgtile::fit {
namespace {

using kernel::PrimitiveType;
using kernel::Vec3;
using testing::Cloud;

struct Fitted {
  RansacResult shapes;
  FittedPrimitives primitives;
};

Fitted fit(const Cloud& c, double epsilon = 0.01) {
  RansacOptions o;
  o.epsilon = epsilon;
  o.min_points = 50;
  o.seed = 3;
  const auto normals = estimate_normals(c.points, {});
  auto shapes = detect_shapes(c.points, normals, o);
  EXPECT_TRUE(shapes.ok());
  Fitted f;
  f.shapes = shapes.value();
  f.primitives = primitives_from_shapes(c.points, normals, f.shapes, PrimitiveOptions{}, o, 0);
  return f;
}

Vec3 box_centre(const kernel::PrimitiveSpec& s) { return s.placement.apply_point(0.5 * s.size); }

// The boxes among the fitted primitives, in their order.
std::vector<kernel::PrimitiveSpec> boxes_of(const FittedPrimitives& f) {
  std::vector<kernel::PrimitiveSpec> boxes;
  for (const auto& p : f.primitives) {
    if (p.spec.type == PrimitiveType::Box) boxes.push_back(p.spec);
  }
  return boxes;
}

// Every rejection with its reason, for failure messages.
std::string rejections(const FittedPrimitives& f) {
  std::string why;
  for (const auto& r : f.rejected) why += r.what + ": " + r.reason + "; ";
  return why;
}

TEST(FitPrimitives, BeamSeenFromThreeSidesIsOneBox) {
  // A 3 × 0.2 × 0.3 beam turned 30° about z, scanned on its two long sides and
  // its bottom.
  const double turn = 30.0 * std::numbers::pi / 180.0;
  const Vec3 ex(std::cos(turn), std::sin(turn), 0.0), ey(-std::sin(turn), std::cos(turn), 0.0);
  const Vec3 ez = Vec3::UnitZ();
  const Vec3 corner(2.0, -1.0, 3.7);
  const Vec3 lx = 3.0 * ex, ly = 0.2 * ey, lz = 0.3 * ez;
  Cloud c = testing::rectangle_cloud(corner, lz, lx, 0.01, 0.002, 1);  // y = 0 side
  c.append(testing::rectangle_cloud(corner + ly, lx, lz, 0.01, 0.002,
                                    2));                               // y = 0.2 side
  c.append(testing::rectangle_cloud(corner, lx, ly, 0.01, 0.002, 3));  // bottom
  const Fitted f = fit(c);
  ASSERT_EQ(f.primitives.primitives.size(), 1U);
  const auto& p = f.primitives.primitives[0];
  ASSERT_EQ(p.spec.type, PrimitiveType::Box);
  const Vec3 expected_centre = corner + 0.5 * (lx + ly + lz);
  EXPECT_LT((box_centre(p.spec) - expected_centre).norm(), 0.02);
  std::vector<double> size{p.spec.size.x(), p.spec.size.y(), p.spec.size.z()};
  std::sort(size.begin(), size.end());
  EXPECT_NEAR(size[0], 0.2, 0.02);
  EXPECT_NEAR(size[1], 0.3, 0.02);
  EXPECT_NEAR(size[2], 3.0, 0.02);
  // The long edge runs along the beam.
  Vec3 long_axis = p.spec.placement.rotation().col(0);
  if (p.spec.size.y() > p.spec.size.x() && p.spec.size.y() > p.spec.size.z()) {
    long_axis = p.spec.placement.rotation().col(1);
  } else if (p.spec.size.z() > p.spec.size.x()) {
    long_axis = p.spec.placement.rotation().col(2);
  }
  EXPECT_LT(testing::line_angle_deg(long_axis, ex), 1.0);
  ASSERT_TRUE(p.quality.has_value());
  EXPECT_GT(p.quality->inliers,
            static_cast<long long>(0.95 * static_cast<double>(c.points.size())));
  EXPECT_LT(p.quality->rms, 0.005);
  EXPECT_GT(p.quality->coverage, 0.3);
  EXPECT_EQ(p.id, "r0-0");
}

// The sorted sizes of a box spec, smallest first.
std::vector<double> sorted_size(const kernel::PrimitiveSpec& s) {
  std::vector<double> size{s.size.x(), s.size.y(), s.size.z()};
  std::sort(size.begin(), size.end());
  return size;
}

// A beam's far side seen at a grazing angle: a few dozen points, too few for a
// plane of the RANSAC's min_points (50 here). The box gets its width from those
// points all the same.
TEST(FitPrimitives, BeamWhoseFarSideIsTooSparseForAPlaneKeepsItsWidth) {
  const Vec3 corner(0.0, 0.0, 3.7);
  const Vec3 lx(3.0, 0.0, 0.0), ly(0.0, 0.2, 0.0), lz(0.0, 0.0, 0.3);
  Cloud c = testing::rectangle_cloud(corner, lz, lx, 0.01, 0.002, 1);  // y = 0 side
  c.append(testing::rectangle_cloud(corner + ly, lx, lz, 0.17, 0.002,
                                    2));  // y = 0.2: ~30
  ASSERT_LT(c.points.size(), 9000U + 50U);
  // Normals as the scan's geometry gives them: estimated ones on so sparse a
  // face lean towards the dense side 0.2 m away, a matter for normal
  // estimation, not for boxes.
  RansacOptions o;
  o.epsilon = 0.01;
  o.min_points = 50;
  o.seed = 3;
  Fitted f;
  auto shapes = detect_shapes(c.points, c.normals, o);
  ASSERT_TRUE(shapes.ok());
  f.shapes = shapes.value();
  f.primitives = primitives_from_shapes(c.points, c.normals, f.shapes, PrimitiveOptions{}, o, 0);
  ASSERT_EQ(f.shapes.shapes.size(), 1U) << "the sparse side must not be a plane of its own";
  ASSERT_EQ(f.primitives.primitives.size(), 1U);
  const auto& p = f.primitives.primitives[0].spec;
  ASSERT_EQ(p.type, PrimitiveType::Box);
  EXPECT_LT((box_centre(p) - (corner + 0.5 * (lx + ly + lz))).norm(), 0.02);
  EXPECT_NEAR(sorted_size(p)[0], 0.2, 0.02);
}

// A beam seen on one long side and underneath only (the scanner below it on
// that side): the underside bridges from the side to where the box ends, no
// opposite face is needed.
TEST(FitPrimitives, BeamSeenOnOneSideAndBelowIsOneBox) {
  const Vec3 corner(1.0, 2.0, 3.7);
  const Vec3 lx(0.0, 3.0, 0.0), ly(-0.2, 0.0, 0.0), lz(0.0, 0.0, 0.3);
  Cloud c = testing::rectangle_cloud(corner, lz, lx, 0.01, 0.002, 3);  // side
  c.append(testing::rectangle_cloud(corner, lx, ly, 0.02, 0.002,
                                    4));  // underside, sparser
  const Fitted f = fit(c);
  ASSERT_EQ(f.primitives.primitives.size(), 1U);
  const auto& p = f.primitives.primitives[0].spec;
  ASSERT_EQ(p.type, PrimitiveType::Box);
  EXPECT_LT((box_centre(p) - (corner + 0.5 * (lx + ly + lz))).norm(), 0.02);
  const auto size = sorted_size(p);
  EXPECT_NEAR(size[0], 0.2, 0.02);
  EXPECT_NEAR(size[1], 0.3, 0.02);
  EXPECT_NEAR(size[2], 3.0, 0.02);
}

// A post standing in front of a beam casts a shadow across its side: the side's
// plane comes in two pieces, but the underside (seen from elsewhere) spans the
// shadow, so the beam is one box over its whole length, not two half-beams.
TEST(FitPrimitives, BeamWithAShadowAcrossItsSideIsOneBox) {
  const Vec3 corner(0.0, 0.0, 3.7);
  const Vec3 ex = Vec3::UnitX(), ly(0.0, 0.2, 0.0), lz(0.0, 0.0, 0.3);
  Cloud c = testing::rectangle_cloud(corner, lz, 1.3 * ex, 0.01, 0.002, 5);
  c.append(testing::rectangle_cloud(corner + 1.7 * ex, lz, 1.3 * ex, 0.01, 0.002, 6));
  c.append(testing::rectangle_cloud(corner, 3.0 * ex, ly, 0.015, 0.002,
                                    7));  // underside
  const Fitted f = fit(c);
  ASSERT_EQ(f.primitives.primitives.size(), 1U);
  const auto& p = f.primitives.primitives[0].spec;
  EXPECT_LT((box_centre(p) - (corner + 0.5 * (3.0 * ex + ly + lz))).norm(), 0.02);
  EXPECT_NEAR(sorted_size(p)[2], 3.0, 0.02);
}

// The fit with the cloud's own normals (as the scan's geometry gives them).
Fitted fit_given_normals(const Cloud& c) {
  RansacOptions o;
  o.epsilon = 0.01;
  o.min_points = 50;
  o.seed = 3;
  auto shapes = detect_shapes(c.points, c.normals, o);
  EXPECT_TRUE(shapes.ok());
  Fitted f;
  f.shapes = shapes.value();
  f.primitives = primitives_from_shapes(c.points, c.normals, f.shapes, PrimitiveOptions{}, o, 0);
  return f;
}

// A shadow 0.4 m wide across the only dense side of a beam, its far side too
// sparse to bridge it point to point (0.17 m apart): the same section goes on
// beyond the shadow, so the two pieces of the side are one box over the whole
// length, not a half-beam and a rejected piece.
TEST(FitPrimitives, BeamWhoseOnlyDenseSideIsShadowedIsOneBox) {
  const Vec3 corner(0.0, 0.0, 3.7);
  const Vec3 ex = Vec3::UnitX(), ly(0.0, 0.2, 0.0), lz(0.0, 0.0, 0.3);
  Cloud c = testing::rectangle_cloud(corner, lz, 1.3 * ex, 0.01, 0.002, 21);
  c.append(testing::rectangle_cloud(corner + 1.7 * ex, lz, 1.3 * ex, 0.01, 0.002, 22));
  c.append(testing::rectangle_cloud(corner + ly, 3.0 * ex, lz, 0.17, 0.002,
                                    23));  // far side
  const Fitted f = fit_given_normals(c);
  ASSERT_EQ(f.primitives.primitives.size(), 1U);
  const auto& p = f.primitives.primitives[0].spec;
  ASSERT_EQ(p.type, PrimitiveType::Box);
  EXPECT_LT((box_centre(p) - (corner + 0.5 * (3.0 * ex + ly + lz))).norm(), 0.02);
  EXPECT_NEAR(sorted_size(p)[2], 3.0, 0.02);
  EXPECT_NEAR(sorted_size(p)[0], 0.2, 0.02);
}

// A sparse face's estimated normals straddle its edges (the neighbourhood
// reaches the next face): here the far side of a beam beyond the end of its
// dense side, normals halfway between the side and the underside, in the
// section's plane. Points on the section's outline still carry the box along:
// one box over the whole length.
TEST(FitPrimitives, BeamContinuedByFacePointsWithStraddlingNormalsIsOneBox) {
  const Vec3 corner(0.0, 0.0, 3.7);
  const Vec3 ex = Vec3::UnitX(), ly(0.0, 0.2, 0.0), lz(0.0, 0.0, 0.3);
  Cloud c = testing::rectangle_cloud(corner, lz, 1.3 * ex, 0.01, 0.002, 31);  // side
  c.append(testing::rectangle_cloud(corner + ly, 1.3 * ex, lz, 0.04, 0.002,
                                    32));  // far side
  Cloud straddling =
      testing::rectangle_cloud(corner + ly + 1.3 * ex, 1.7 * ex, lz, 0.02, 0.002, 33);
  for (auto& n : straddling.normals) n = Vec3(0.0, 0.6, -0.8);
  c.append(straddling);
  const Fitted f = fit_given_normals(c);
  ASSERT_EQ(f.primitives.primitives.size(), 1U);
  const auto& p = f.primitives.primitives[0].spec;
  ASSERT_EQ(p.type, PrimitiveType::Box);
  EXPECT_LT((box_centre(p) - (corner + 0.5 * (3.0 * ex + ly + lz))).norm(), 0.02);
  EXPECT_NEAR(sorted_size(p)[2], 3.0, 0.02);
}

// Posts standing in a row beyond a beam's end, their surfaces 1.5 cm off the
// plane of its side: their points lie on the box's outline with normals across
// its length, but they belong to cylinders across the length, members the beam
// meets, not its faces. The box keeps its own 2 m, whatever the shadow-gap rule
// would bridge between the posts.
TEST(FitPrimitives, PostsInARowBeyondABeamDoNotLengthenIt) {
  const Vec3 corner(0.0, 0.0, 3.7);
  const Vec3 lx(2.0, 0.0, 0.0), ly(0.0, 0.2, 0.0), lz(0.0, 0.0, 0.3);
  Cloud c = testing::rectangle_cloud(corner, lz, lx, 0.01, 0.002, 41);   // side y = 0
  c.append(testing::rectangle_cloud(corner, lx, ly, 0.015, 0.002, 42));  // underside
  c.append(testing::rectangle_cloud(corner + ly, lx, lz, 0.01, 0.002,
                                    43));  // side y = 0.2
  for (int k = 0; k < 4; ++k) {
    c.append(testing::cylinder_cloud(Vec3(2.3 + 0.45 * k, -0.165, 3.2), Vec3::UnitZ(), 0.15, 1.3,
                                     0.0, 2.0 * std::numbers::pi, 3000, 0.002,
                                     static_cast<std::uint64_t>(44 + k)));
  }
  const Fitted f = fit(c);
  int boxes = 0, cylinders = 0;
  for (const auto& p : f.primitives.primitives) {
    if (p.spec.type == PrimitiveType::Box) {
      ++boxes;
      EXPECT_NEAR(sorted_size(p.spec)[2], 2.0, 0.03) << "the box runs on along the posts";
      EXPECT_LT((box_centre(p.spec) - (corner + 0.5 * (lx + ly + lz))).norm(), 0.02);
    }
    cylinders += p.spec.type == PrimitiveType::Cylinder ? 1 : 0;
  }
  EXPECT_EQ(boxes, 1);
  EXPECT_EQ(cylinders, 4);
}

// Two collinear beams abutting a crossing beam from either side (a node of a
// timber grid), their sides and undersides coplanar across the node. The
// crossing beam, scanned densest, is built first; its points in the node tell
// the others that a member crosses there, so the shadow-gap rule does not carry
// either across it: three boxes, not a crossing beam and one long beam through
// it. Each collinear beam's end then reaches the crossing member's middle (the
// joint is hidden; members meet there), so each is 1.5 m long.
TEST(FitPrimitives, TwoCollinearBeamsCrossingAThirdAreThreeBoxes) {
  const Vec3 ex = Vec3::UnitX(), ey = Vec3::UnitY(), lz(0.0, 0.0, 0.3);
  Cloud c;
  // The crossing beam along y: x in [-0.1, 0.1], its sides hidden where the
  // others abut.
  for (const double x : {-0.1, 0.1}) {
    c.append(testing::rectangle_cloud(Vec3(x, -1.5, 3.7), 1.4 * ey, lz, 0.007, 0.002, 51));
    c.append(testing::rectangle_cloud(Vec3(x, 0.1, 3.7), 1.4 * ey, lz, 0.007, 0.002, 52));
  }
  c.append(testing::rectangle_cloud(Vec3(-0.1, -1.5, 3.7), 0.2 * ex, 3.0 * ey, 0.01, 0.002, 53));
  // The collinear beams along x, each 1.4 m of visible length.
  std::uint64_t seed = 54;
  for (const double x0 : {-1.5, 0.1}) {
    for (const double y : {-0.1, 0.1}) {
      c.append(testing::rectangle_cloud(Vec3(x0, y, 3.7), 1.4 * ex, lz, 0.01, 0.002, seed++));
    }
    c.append(
        testing::rectangle_cloud(Vec3(x0, -0.1, 3.7), 1.4 * ex, 0.2 * ey, 0.015, 0.002, seed++));
  }
  // Boxes only: the node's cross-shaped section would otherwise be one
  // extrusion, which is not what this test is about.
  RansacOptions o;
  o.epsilon = 0.01;
  o.min_points = 50;
  o.seed = 3;
  PrimitiveOptions boxes_only;
  boxes_only.extrusions = false;
  boxes_only.revolutions = false;
  const auto normals = estimate_normals(c.points, {});
  auto shapes = detect_shapes(c.points, normals, o);
  ASSERT_TRUE(shapes.ok());
  Fitted f;
  f.shapes = shapes.value();
  f.primitives = primitives_from_shapes(c.points, normals, f.shapes, boxes_only, o, 0);
  std::vector<kernel::PrimitiveSpec> boxes = boxes_of(f.primitives);
  const std::string why = rejections(f.primitives);
  ASSERT_EQ(boxes.size(), 3U) << why;
  std::sort(boxes.begin(), boxes.end(),
            [](const auto& a, const auto& b) { return box_centre(a).x() < box_centre(b).x(); });
  EXPECT_LT((box_centre(boxes[0]) - Vec3(-0.75, 0.0, 3.85)).norm(), 0.02);
  EXPECT_LT((box_centre(boxes[1]) - Vec3(0.0, 0.0, 3.85)).norm(), 0.02);
  EXPECT_LT((box_centre(boxes[2]) - Vec3(0.75, 0.0, 3.85)).norm(), 0.02);
  EXPECT_NEAR(sorted_size(boxes[0])[2], 1.5, 0.03);
  EXPECT_NEAR(sorted_size(boxes[1])[2], 3.0, 0.03);
  EXPECT_NEAR(sorted_size(boxes[2])[2], 1.5, 0.03);
}

// Two beams meeting end to end at a post that stands wider than they are (the
// gate's junctions): their sides are coplanar, their undersides one plane, but
// the post between them ends each: two boxes, not one through the post. The
// post's top is hidden in them (its fit ends at their undersides): each beam's
// end still reaches its axis, where the members meet, so each box runs 2.888 m
// from its far end to x = 0.
TEST(FitPrimitives, TwoBeamsMeetingAtAPostAreTwoBoxes) {
  const Vec3 ly(0.0, 0.2, 0.0), lz(0.0, 0.0, 0.3), ex = Vec3::UnitX();
  Cloud c;
  std::uint64_t seed = 10;
  for (const double x0 : {-2.888, 0.112}) {  // each beam 2.776 m long, a post at x = 0
    const Vec3 corner(x0, -0.1, 3.7);
    c.append(testing::rectangle_cloud(corner, lz, 2.776 * ex, 0.01, 0.002, seed++));
    c.append(testing::rectangle_cloud(corner + ly, 2.776 * ex, lz, 0.01, 0.002, seed++));
    c.append(testing::rectangle_cloud(corner, 2.776 * ex, ly, 0.015, 0.002, seed++));
  }
  // The post below the beams (radius 0.15, up to their undersides), its top
  // hidden in them.
  c.append(testing::cylinder_cloud(Vec3(0, 0, 2.7), Vec3::UnitZ(), 0.15, 1.0, 0.0,
                                   2.0 * std::numbers::pi, 3000, 0.002, seed++));
  const Fitted f = fit(c);
  std::vector<Vec3> centres;
  for (const auto& p : f.primitives.primitives) {
    if (p.spec.type != PrimitiveType::Box) continue;
    centres.push_back(box_centre(p.spec));
    EXPECT_NEAR(sorted_size(p.spec)[2], 2.888, 0.03);
  }
  ASSERT_EQ(centres.size(), 2U);
  std::sort(centres.begin(), centres.end(),
            [](const Vec3& a, const Vec3& b) { return a.x() < b.x(); });
  EXPECT_LT((centres[0] - Vec3(-1.444, 0.0, 3.85)).norm(), 0.02);
  EXPECT_LT((centres[1] - Vec3(1.444, 0.0, 3.85)).norm(), 0.02);
}

// A beam 3 m long whose sides and underside the scan saw in two pieces, a
// shadow 0.8 m long across all of them (longer than the gap a face's points are
// followed over): two boxes of one section on one line with nothing between
// them are one member over the whole length.
TEST(FitPrimitives, BeamSeenInTwoPiecesIsOneMember) {
  const Vec3 ex = Vec3::UnitX(), ly(0.0, 0.2, 0.0), lz(0.0, 0.0, 0.3);
  Cloud c;
  std::uint64_t seed = 80;
  for (const double x0 : {0.0, 1.9}) {  // pieces [0, 1.1] and [1.9, 3.0]
    const Vec3 corner(x0, 0.0, 3.7);
    c.append(testing::rectangle_cloud(corner, lz, 1.1 * ex, 0.01, 0.002, seed++));
    c.append(testing::rectangle_cloud(corner + ly, 1.1 * ex, lz, 0.01, 0.002, seed++));
    c.append(testing::rectangle_cloud(corner, 1.1 * ex, ly, 0.015, 0.002, seed++));
  }
  const Fitted f = fit(c);
  ASSERT_EQ(f.primitives.primitives.size(), 1U) << rejections(f.primitives);
  const auto& p = f.primitives.primitives[0].spec;
  ASSERT_EQ(p.type, PrimitiveType::Box);
  EXPECT_LT((box_centre(p) - Vec3(1.5, 0.1, 3.85)).norm(), 0.02);
  EXPECT_NEAR(sorted_size(p)[2], 3.0, 0.03);
  EXPECT_EQ(f.primitives.primitives[0].id, "r0-0");
}

// The same two pieces with their end faces seen across the gap (two beams, not
// one in a shadow): points facing along the line between them keep them apart.
TEST(FitPrimitives, TwoBeamsWithTheirEndsSeenStayTwo) {
  const Vec3 ex = Vec3::UnitX(), ly(0.0, 0.2, 0.0), lz(0.0, 0.0, 0.3);
  Cloud c;
  std::uint64_t seed = 90;
  for (const double x0 : {0.0, 1.9}) {
    const Vec3 corner(x0, 0.0, 3.7);
    c.append(testing::rectangle_cloud(corner, lz, 1.1 * ex, 0.01, 0.002, seed++));
    c.append(testing::rectangle_cloud(corner + ly, 1.1 * ex, lz, 0.01, 0.002, seed++));
    c.append(testing::rectangle_cloud(corner, 1.1 * ex, ly, 0.015, 0.002, seed++));
  }
  c.append(testing::rectangle_cloud(Vec3(1.1, 0.0, 3.7), ly, lz, 0.01, 0.002, seed++));
  c.append(testing::rectangle_cloud(Vec3(1.9, 0.0, 3.7), lz, ly, 0.01, 0.002, seed++));
  const Fitted f = fit(c);
  std::vector<double> lengths;
  for (const auto& p : f.primitives.primitives) {
    if (p.spec.type == PrimitiveType::Box) lengths.push_back(sorted_size(p.spec)[2]);
  }
  ASSERT_EQ(lengths.size(), 2U);
  for (const double l : lengths) EXPECT_NEAR(l, 1.1, 0.03);
}

// The cloud without its points inside the axis-aligned box [lo, hi] (a column's
// surface where a beam covers it: the scan never sees it).
Cloud without_box(const Cloud& c, const Vec3& lo, const Vec3& hi) {
  Cloud out;
  for (std::size_t i = 0; i < c.points.size(); ++i) {
    const Vec3& p = c.points[i];
    if ((p.array() >= lo.array()).all() && (p.array() <= hi.array()).all()) continue;
    out.points.push_back(p);
    out.normals.push_back(c.normals[i]);
  }
  return out;
}

// A beam running into a column (radius 0.15), seen up to the column's surface:
// its end reaches the column's axis, where the frame's members meet, so that
// the two overlap and fuse into one solid instead of touching along a line.
TEST(FitPrimitives, BeamEndingInAColumnReachesItsAxis) {
  const Vec3 ex = Vec3::UnitX(), ly(0.0, 0.2, 0.0), lz(0.0, 0.0, 0.3);
  Cloud c = without_box(testing::cylinder_cloud(Vec3(0, 0, 0), Vec3::UnitZ(), 0.15, 4.0, 0.0,
                                                2.0 * std::numbers::pi, 6000, 0.002, 100),
                        Vec3(-1, -0.1, 3.3), Vec3(1, 0.1, 3.6));
  const double x0 = std::sqrt(0.15 * 0.15 - 0.1 * 0.1);  // where the beam's sides leave it
  const Vec3 corner(x0, -0.1, 3.3);
  c.append(testing::rectangle_cloud(corner, lz, (3.0 - x0) * ex, 0.01, 0.002, 101));
  c.append(testing::rectangle_cloud(corner + ly, (3.0 - x0) * ex, lz, 0.01, 0.002, 102));
  c.append(testing::rectangle_cloud(corner, (3.0 - x0) * ex, ly, 0.015, 0.002, 103));
  const Fitted f = fit(c);
  const std::vector<kernel::PrimitiveSpec> boxes = boxes_of(f.primitives);
  const auto cylinders =
      std::count_if(f.primitives.primitives.begin(), f.primitives.primitives.end(),
                    [](const auto& p) { return p.spec.type == PrimitiveType::Cylinder; });
  ASSERT_EQ(cylinders, 1);
  ASSERT_EQ(boxes.size(), 1U);
  EXPECT_NEAR(sorted_size(boxes[0])[2], 3.0, 0.03);
  EXPECT_LT((box_centre(boxes[0]) - Vec3(1.5, 0.0, 3.45)).norm(), 0.02);
}

// Two columns (radius 0.15, 4 m, at x = 0 and 3 on y = 0) whose surface a beam
// of 0.2 x 0.3 between them hides (y in [-0.1, 0.1], z in [3.3, 3.6]); seeds
// from `seed` on.
Cloud two_columns(std::uint64_t& seed) {
  Cloud c;
  for (const double x : {0.0, 3.0}) {
    c.append(without_box(testing::cylinder_cloud(Vec3(x, 0, 0), Vec3::UnitZ(), 0.15, 4.0, 0.0,
                                                 2.0 * std::numbers::pi, 6000, 0.002, seed++),
                         Vec3(x - 1, -0.1, 3.3), Vec3(x + 1, 0.1, 3.6)));
  }
  return c;
}

// A sibling beam 3 m from the columns' line (y in [2.9, 3.1], z in [3.3, 3.6],
// x in [0, 3]), seen on both sides and below.
void add_sibling_beam(Cloud& c, std::uint64_t& seed) {
  const Vec3 ex = Vec3::UnitX(), ly(0.0, 0.2, 0.0), lz(0.0, 0.0, 0.3);
  const Vec3 sibling(0.0, 2.9, 3.3);
  c.append(testing::rectangle_cloud(sibling, lz, 3.0 * ex, 0.01, 0.002, seed++));
  c.append(testing::rectangle_cloud(sibling + ly, 3.0 * ex, lz, 0.01, 0.002, seed++));
  c.append(testing::rectangle_cloud(sibling, 3.0 * ex, ly, 0.015, 0.002, seed++));
}

// A beam (0.2 x 0.3) between two columns (radius 0.15, at x = 0 and 3 on y = 0)
// seen whole over its first metre and, behind a shadow 1.4 m long, only as a
// sparse strip of one side before the far column (too few points for a box of
// its own): the free end goes on to that column's axis although the shadow is
// longer than the piece seen, because the beam's face is seen again before the
// column. Without the strip it stops where its points stop.
TEST(FitPrimitives, BeamSeenAgainBehindALongShadowReachesTheFarColumn) {
  const Vec3 ex = Vec3::UnitX(), ly(0.0, 0.2, 0.0), lz(0.0, 0.0, 0.3);
  auto scene = [&](bool strip) {
    std::uint64_t seed = 120;
    Cloud c = two_columns(seed);
    const double x0 = std::sqrt(0.15 * 0.15 - 0.1 * 0.1);
    const Vec3 corner(x0, -0.1, 3.3);
    c.append(testing::rectangle_cloud(corner, lz, (1.0 - x0) * ex, 0.01, 0.002, seed++));
    c.append(testing::rectangle_cloud(corner + ly, (1.0 - x0) * ex, lz, 0.01, 0.002, seed++));
    c.append(testing::rectangle_cloud(corner, (1.0 - x0) * ex, ly, 0.015, 0.002, seed++));
    if (strip) {
      c.append(testing::rectangle_cloud(Vec3(2.4, -0.1, 3.3), lz, 0.45 * ex, 0.05, 0.002, seed));
    }
    return c;
  };
  for (const bool strip : {true, false}) {
    const Fitted f = fit(scene(strip));
    const std::vector<kernel::PrimitiveSpec> boxes = boxes_of(f.primitives);
    ASSERT_EQ(boxes.size(), 1U) << rejections(f.primitives);
    if (strip) {
      EXPECT_NEAR(sorted_size(boxes[0])[2], 3.0, 0.03);
      EXPECT_LT((box_centre(boxes[0]) - Vec3(1.5, 0.0, 3.45)).norm(), 0.02);
    } else {
      EXPECT_NEAR(sorted_size(boxes[0])[2], 1.0, 0.05);
    }
  }
}

// A beam (0.2 x 0.3) between two columns (radius 0.15, at x = 0 and 3 on y = 0)
// seen on one side only, over its middle 1.4 m (shadows at both ends), and a
// parallel sibling beam 3 m away seen on both sides and below. The first takes
// the section its sibling shows, on the side of its face where its centre line
// runs through the columns' axes, and its free ends go on to them: one box from
// axis to axis.
TEST(FitPrimitives, BeamSeenOnOneFaceTakesItsSiblingsSectionAndReachesTheColumns) {
  const Vec3 ex = Vec3::UnitX(), ly(0.0, 0.2, 0.0), lz(0.0, 0.0, 0.3);
  std::uint64_t seed = 110;
  Cloud c = two_columns(seed);
  add_sibling_beam(c, seed);
  c.append(testing::rectangle_cloud(Vec3(0.8, -0.1, 3.3), lz, 1.4 * ex, 0.01, 0.002, seed++));
  const Fitted f = fit(c);
  std::vector<kernel::PrimitiveSpec> boxes = boxes_of(f.primitives);
  const std::string why = rejections(f.primitives);
  ASSERT_EQ(boxes.size(), 2U) << why;
  std::sort(boxes.begin(), boxes.end(),
            [](const auto& a, const auto& b) { return box_centre(a).y() < box_centre(b).y(); });
  for (std::size_t k = 0; k < 2; ++k) {
    const auto size = sorted_size(boxes[k]);
    EXPECT_NEAR(size[0], 0.2, 0.02);
    EXPECT_NEAR(size[1], 0.3, 0.02);
    EXPECT_NEAR(size[2], 3.0, 0.03);
    EXPECT_LT((box_centre(boxes[k]) - Vec3(1.5, 3.0 * static_cast<double>(k), 3.45)).norm(), 0.02);
  }
}

// The same one-face beam, its face seen in three pieces of one plane (0.5, 0.5
// and 0.4 m long: each shorter than three times its 0.3 m width, shadows of 0.4
// m between them): the pieces, with no column between them, are one face, and
// the beam one box from axis to axis.
TEST(FitPrimitives, BeamFaceSeenInPiecesIsOneMember) {
  const Vec3 ex = Vec3::UnitX(), ly(0.0, 0.2, 0.0), lz(0.0, 0.0, 0.3);
  std::uint64_t seed = 130;
  Cloud c = two_columns(seed);
  add_sibling_beam(c, seed);
  for (const auto& [x0, length] : {std::pair{0.4, 0.5}, {1.3, 0.5}, {2.2, 0.4}}) {
    c.append(testing::rectangle_cloud(Vec3(x0, -0.1, 3.3), lz, length * ex, 0.01, 0.002, seed++));
  }
  const Fitted f = fit(c);
  std::vector<kernel::PrimitiveSpec> boxes = boxes_of(f.primitives);
  ASSERT_EQ(boxes.size(), 2U) << rejections(f.primitives);
  std::sort(boxes.begin(), boxes.end(),
            [](const auto& a, const auto& b) { return box_centre(a).y() < box_centre(b).y(); });
  const auto size = sorted_size(boxes[0]);
  EXPECT_NEAR(size[0], 0.2, 0.02);
  EXPECT_NEAR(size[1], 0.3, 0.02);
  EXPECT_NEAR(size[2], 3.0, 0.03);
  EXPECT_LT((box_centre(boxes[0]) - Vec3(1.5, 0.0, 3.45)).norm(), 0.02);
}

// Columns whose tops the beam they carry hides (the scan sees them up to 3.6 m,
// the beam lies over 3.7-4.0 m between them): the columns are fitted 3.6 m
// high, below the beam's centre line, and the beam's ends still reach their
// axes.
TEST(FitPrimitives, BeamOverHiddenColumnTopsReachesTheirAxes) {
  const Vec3 ex = Vec3::UnitX(), ly(0.0, 0.2, 0.0), lz(0.0, 0.0, 0.3);
  Cloud c;
  std::uint64_t seed = 140;
  for (const double x : {0.0, 3.0}) {
    c.append(testing::cylinder_cloud(Vec3(x, 0, 0), Vec3::UnitZ(), 0.15, 3.6, 0.0,
                                     2.0 * std::numbers::pi, 6000, 0.002, seed++));
  }
  const double x0 = std::sqrt(0.15 * 0.15 - 0.1 * 0.1);  // where the beam's sides leave them
  const Vec3 corner(x0, -0.1, 3.7);
  const Vec3 along = (3.0 - 2.0 * x0) * ex;
  c.append(testing::rectangle_cloud(corner, lz, along, 0.01, 0.002, seed++));
  c.append(testing::rectangle_cloud(corner + ly, along, lz, 0.01, 0.002, seed++));
  c.append(testing::rectangle_cloud(corner, along, ly, 0.015, 0.002, seed++));
  const Fitted f = fit(c);
  const std::vector<kernel::PrimitiveSpec> boxes = boxes_of(f.primitives);
  ASSERT_EQ(boxes.size(), 1U) << rejections(f.primitives);
  EXPECT_NEAR(sorted_size(boxes[0])[2], 3.0, 0.03);
  EXPECT_LT((box_centre(boxes[0]) - Vec3(1.5, 0.0, 3.85)).norm(), 0.02);
}

// A narrow strip of a column that the RANSAC took for a plane (a flat-enough
// piece of a sparse cylinder) bows across its width: no box is built on it, the
// reason says why.
TEST(FitPrimitives, StripOfAColumnIsNoBox) {
  const Cloud c =
      testing::cylinder_cloud(Vec3(0, 0, 0), Vec3::UnitZ(), 0.15, 3.5, -0.6, 0.6, 1500, 0.001, 12);
  RansacOptions o;
  o.epsilon = 0.02;  // loose enough for one plane to take the whole strip
  o.min_points = 50;
  o.seed = 3;
  o.shapes = {true, false, false, false, false};  // planes only: the strip is a plane
  const auto normals = estimate_normals(c.points, {});
  const auto shapes = detect_shapes(c.points, normals, o);
  ASSERT_TRUE(shapes.ok());
  ASSERT_FALSE(shapes.value().shapes.empty());
  const auto fitted = primitives_from_shapes(c.points, normals, shapes.value(), {}, o, 0);
  for (const auto& p : fitted.primitives) EXPECT_NE(p.spec.type, PrimitiveType::Box);
  bool said = false;
  for (const auto& r : fitted.rejected) said = said || r.reason.find("bow") != std::string::npos;
  EXPECT_TRUE(said);
}

// Level terrain at z = 0 over [-5, n - 5] in x and y, one-metre cells.
GroundGrid level_ground(int n) {
  GroundGrid ground;
  ground.x0 = -5;
  ground.y0 = -5;
  ground.cell = 1.0;
  ground.nx = ground.ny = n;
  ground.z.assign(static_cast<std::size_t>(n) * static_cast<std::size_t>(n), 0.0);
  return ground;
}

// The primitives made of the shapes the RANSAC finds in `c` (normals estimated), `options`
// over `ground`.
FittedPrimitives fit_over(const Cloud& c, double epsilon, long long min_points,
                          PrimitiveOptions options, const GroundGrid& ground) {
  RansacOptions o;
  o.epsilon = epsilon;
  o.min_points = min_points;
  o.seed = 3;
  const auto normals = estimate_normals(c.points, {});
  const auto shapes = detect_shapes(c.points, normals, o);
  EXPECT_TRUE(shapes.ok());
  if (!shapes.ok()) return {};
  options.ground = &ground;
  return primitives_from_shapes(c.points, normals, shapes.value(), options, o, 0);
}

// A beam's underside seen from below with terrain under it: no box from the
// ground up to it (only roofs wide enough to be buildings reach down to the
// terrain).
TEST(FitPrimitives, BeamUndersideIsNoBuildingOverTheGround) {
  const Cloud c =
      testing::rectangle_cloud(Vec3(0, 0, 3.7), Vec3(3, 0, 0), Vec3(0, 0.2, 0), 0.01, 0.002, 13);
  EXPECT_TRUE(fit_over(c, 0.01, 50, PrimitiveOptions{}, level_ground(10)).primitives.empty());
}

// A pitched roof seen from the air twice, by two flight strips 6 cm apart in height (strips
// are registered to a few centimetres), whose building no other step makes: a surface with no
// depth of its own, not a box 6 cm thick floating 8 m over the terrain (as on the ISPRS
// Stuttgart site, pcl/CSite3_orig-utm.pcd, where twelve such slabs stood on roofs and streets).
TEST(FitPrimitives, RoofSeenTwiceIsNoSlabOverTheTerrain) {
  const Vec3 corner(0, 0, 8), along(10, 0, 0), up_slope(0, 4, 2);
  Cloud c = testing::rectangle_cloud(corner, along, up_slope, 0.3, 0.01, 21);
  const Vec3 n = along.cross(up_slope).normalized();
  const Cloud second = testing::rectangle_cloud(corner - 0.06 / n.z() * Vec3::UnitZ(), along,
                                                up_slope, 0.3, 0.01, 22);
  c.points.insert(c.points.end(), second.points.begin(), second.points.end());
  PrimitiveOptions options;
  options.roof_partition = false;  // no building step takes it
  options.roof_parts = false;
  options.extrusions = false;
  options.blocks = false;
  const auto fitted = fit_over(c, 0.02, 40, options, level_ground(20));
  EXPECT_TRUE(boxes_of(fitted).empty())
      << boxes_of(fitted).size() << " boxes, thinnest "
      << (boxes_of(fitted).empty() ? 0.0 : boxes_of(fitted)[0].size.minCoeff());
  bool named = false;
  for (const auto& r : fitted.rejected) {
    named = named || r.reason.find("a roof seen from one side") != std::string::npos;
  }
  EXPECT_TRUE(named) << rejections(fitted);
}

TEST(FitPrimitives, CylinderIsBoundedByItsInliers) {
  const Cloud c = testing::cylinder_cloud(Vec3(1, 1, 0), Vec3::UnitZ(), 0.15, 3.7, 0.0,
                                          2.0 * std::numbers::pi, 5000, 0.003, 4);
  const Fitted f = fit(c);
  ASSERT_EQ(f.primitives.primitives.size(), 1U);
  const auto& p = f.primitives.primitives[0].spec;
  ASSERT_EQ(p.type, PrimitiveType::Cylinder);
  EXPECT_NEAR(p.radius, 0.15, 0.005);
  EXPECT_NEAR(p.height, 3.7, 0.03);
  const Vec3 base = p.placement.translation();
  const Vec3 top = p.placement.apply_point(Vec3(0, 0, p.height));
  EXPECT_LT((Vec3(base.x(), base.y(), 0) - Vec3(1, 1, 0)).norm(), 0.005);
  EXPECT_NEAR(std::min(base.z(), top.z()), 0.0, 0.02);
  EXPECT_TRUE(kernel::check_shape(kernel::build_primitive(p).value()).valid());
}

TEST(FitPrimitives, ConeSphereAndTorusBecomeValidSolids) {
  // Similar densities (the connectivity size follows the cloud's typical
  // spacing).
  Cloud c = testing::cone_cloud(Vec3(0, 0, 2), Vec3(0, 0, -1), std::atan(1.2 / 2.0), 0.3, 2.0, 8000,
                                0.003, 5);
  c.append(testing::sphere_cloud(Vec3(20, 0, 8), 2.0, 0.0, 10000, 0.003, 6));
  c.append(testing::torus_cloud(Vec3(-20, 0, 3.45), Vec3::UnitY(), 2.5, 0.35, 15000, 0.003, 7));
  const Fitted f = fit(c);
  EXPECT_EQ(f.primitives.per_type[static_cast<int>(PrimitiveType::Cone)], 1);
  EXPECT_EQ(f.primitives.per_type[static_cast<int>(PrimitiveType::Sphere)], 1);
  EXPECT_EQ(f.primitives.per_type[static_cast<int>(PrimitiveType::Torus)], 1);
  for (const auto& p : f.primitives.primitives) {
    auto solid = kernel::build_primitive(p.spec);
    ASSERT_TRUE(solid.ok());
    EXPECT_TRUE(kernel::check_shape(solid.value()).valid());
    if (p.spec.type == PrimitiveType::Cone) {
      // Radius 1.2 at the base (z = 0), apex at z = 2: the inliers reach from t
      // = 0.3 to 2.
      EXPECT_NEAR(std::max(p.spec.radius, p.spec.radius2), 1.2, 0.02);
      EXPECT_NEAR(p.spec.height, 1.7, 0.03);
    }
    if (p.spec.type == PrimitiveType::Sphere) {
      EXPECT_NEAR(p.spec.radius, 2.0, 0.005);
    }
    if (p.spec.type == PrimitiveType::Torus) {
      EXPECT_NEAR(p.spec.radius, 2.5, 0.01);
      EXPECT_NEAR(p.spec.radius2, 0.35, 0.005);
    }
  }
}

TEST(FitPrimitives, LonePlaneIsRejectedWithAReason) {
  const Cloud c =
      testing::rectangle_cloud(Vec3(0, 0, 0), Vec3(2, 0, 0), Vec3(0, 2, 0), 0.02, 0.002, 8);
  const Fitted f = fit(c);
  EXPECT_TRUE(f.primitives.primitives.empty());
  ASSERT_FALSE(f.primitives.rejected.empty());
  EXPECT_NE(f.primitives.rejected[0].reason.find("no box"), std::string::npos);
}

// Rule 4 (issue #18): a primitive must be supported by its points. A 21.7 m
// sphere fitted to the 49 points of a roof's gentle cap (as over the timber
// gate and over row houses) covers a thousandth of its surface and reaches tens
// of metres past the region: rejected, with the reason counted; a well-seen
// ball is kept.
RansacResult one_shape(const Surface& surface, std::size_t n, double cell) {
  RansacResult r;
  DetectedShape shape;
  shape.surface = surface;
  for (std::uint32_t i = 0; i < n; ++i) shape.inliers.push_back(i);
  r.shapes.push_back(shape);
  r.assignment.assign(n, 0);
  r.cluster_epsilon = cell;
  return r;
}

TEST(FitPrimitives, GiantSphereOverAFewRoofPointsIsRejectedAsUnsupported) {
  const Vec3 centre(3.0, 4.0, -21.2);
  const Cloud c = testing::sphere_cloud(centre, 21.7, 21.2, 49, 0.0, 11);
  Surface s;
  s.type = ShapeType::Sphere;
  s.point = centre;
  s.radius = 21.7;
  const RansacOptions o;
  const FittedPrimitives f = primitives_from_shapes(
      c.points, {}, one_shape(s, c.points.size(), 0.5), PrimitiveOptions{}, o, 0);
  EXPECT_TRUE(f.primitives.empty());
  ASSERT_EQ(f.rejected.size(), 1U);
  EXPECT_EQ(f.rejected[0].reason.rfind("unsupported: ", 0), 0U) << f.rejected[0].reason;
  EXPECT_EQ(f.rejected[0].points, 49);
}

TEST(FitPrimitives, SphereReachingFarBelowItsPointsIsRejectedAsUnsupported) {
  // Densely seen (coverage passes) but the cap is 0.3 m of a 6 m sphere over a
  // 4 m patch: the full sphere hangs 11 m below every point of the region.
  const Vec3 centre(0.0, 0.0, -5.7);
  const Cloud c = testing::sphere_cloud(centre, 6.0, 5.7, 4000, 0.0, 12);
  Surface s;
  s.type = ShapeType::Sphere;
  s.point = centre;
  s.radius = 6.0;
  PrimitiveOptions po;
  po.min_curved_coverage = 0.0;
  const FittedPrimitives f = primitives_from_shapes(
      c.points, {}, one_shape(s, c.points.size(), 0.1), po, RansacOptions{}, 0);
  EXPECT_TRUE(f.primitives.empty());
  ASSERT_EQ(f.rejected.size(), 1U);
  EXPECT_NE(f.rejected[0].reason.find("beyond the points of its region"), std::string::npos)
      << f.rejected[0].reason;
}

TEST(FitPrimitives, WellSeenBallIsKept) {
  const Vec3 centre(1.0, 2.0, 3.0);
  const Cloud c = testing::sphere_cloud(centre, 0.5, -0.5, 3000, 0.0, 13);
  Surface s;
  s.type = ShapeType::Sphere;
  s.point = centre;
  s.radius = 0.5;
  const FittedPrimitives f = primitives_from_shapes(
      c.points, {}, one_shape(s, c.points.size(), 0.05), PrimitiveOptions{}, RansacOptions{}, 0);
  ASSERT_EQ(f.primitives.size(), 1U) << (f.rejected.empty() ? "" : f.rejected[0].reason);
  EXPECT_GT(f.primitives[0].quality->coverage, 0.5);
}

}  // namespace
}  // namespace csgtile::fit
