// Members of a frame (members.cpp): a column's end hidden among the members it carries, or on
// the member it stands on, meets that member's middle.

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "column_ends.h"

namespace csgtile::fit::detail {
namespace {

using kernel::Vec3;

// A box of `size` from its minimum corner.
geo::ScenePrimitive box(const Vec3& corner, const Vec3& size) {
  geo::ScenePrimitive p;
  p.spec.type = kernel::PrimitiveType::Box;
  p.spec.size = size;
  p.spec.placement = kernel::Location::translation(corner);
  return p;
}

// A cylinder of radius r and height h on `base`, its axis turned from z onto `axis`.
geo::ScenePrimitive cylinder(const Vec3& base, double r, double h,
                             const Vec3& axis = Vec3::UnitZ()) {
  geo::ScenePrimitive p;
  p.spec.type = kernel::PrimitiveType::Cylinder;
  p.spec.radius = r;
  p.spec.height = h;
  const Eigen::Matrix3d turn =
      Eigen::Quaterniond::FromTwoVectors(Vec3::UnitZ(), axis).toRotationMatrix();
  p.spec.placement = kernel::Location::from_parts(turn, 1.0, base).value();
  geo::FitQuality q;
  q.inliers = 300;
  q.coverage = 0.8;
  p.quality = q;
  return p;
}

double top_of(const geo::ScenePrimitive& p) {
  return p.spec.placement.translation().z() + p.spec.placement.scale() * p.spec.height;
}

const double kCos = std::cos(5.0 * std::numbers::pi / 180.0);

TEST(FitMembers, AColumnTopHiddenAmongTheBeamsMeetsTheirMiddle) {
  // A beam along x at 3.70–4.00 m, its centre line through the column's axis; the column's
  // points stop 3 cm below it.
  std::vector<geo::ScenePrimitive> prims{cylinder({0, 0, 0}, 0.15, 3.67),
                                         box({0, -0.1, 3.7}, {3, 0.2, 0.3})};
  const std::vector<double> reach{0.05, 0.05};
  EXPECT_EQ(columns_into_members(prims, reach, kCos), 1);
  EXPECT_NEAR(top_of(prims[0]), 3.85, 1e-12);
  EXPECT_NEAR(prims[0].spec.placement.translation().z(), 0.0, 1e-12);  // its foot stays
  EXPECT_NEAR(prims[0].quality->coverage, 0.8 * 3.67 / 3.85, 1e-12);
  EXPECT_EQ(prims[0].quality->inliers, 300);
  EXPECT_EQ(prims[1].spec.size, Vec3(3, 0.2, 0.3));  // the beam is not moved
}

TEST(FitMembers, ABeamStoppingAtTheColumnsSideStillCarriesIt) {
  // The beam's points stop at the column's surface (x = 0.15), not at its axis.
  std::vector<geo::ScenePrimitive> prims{cylinder({0, 0, 0}, 0.15, 3.67),
                                         box({0.15, -0.1, 3.7}, {2.85, 0.2, 0.3})};
  EXPECT_EQ(columns_into_members(prims, std::vector<double>{0.05, 0.05}, kCos), 1);
  EXPECT_NEAR(top_of(prims[0]), 3.85, 1e-12);
}

TEST(FitMembers, APostStandingOnABeamReachesDownIntoIt) {
  // A tilted frame: the beam runs along (1, 1, 0); a post stands 4 cm above its top.
  const Vec3 u = Vec3(1, 1, 0).normalized();
  geo::ScenePrimitive beam;
  beam.spec.type = kernel::PrimitiveType::Box;
  beam.spec.size = Vec3(4, 0.2, 0.3);
  Eigen::Matrix3d r;
  r.col(0) = u;
  r.col(1) = Vec3::UnitZ().cross(u);
  r.col(2) = Vec3::UnitZ();
  beam.spec.placement =
      kernel::Location::from_parts(r, 1.0, Vec3(0, 0, 0) - 0.1 * r.col(1)).value();
  const Vec3 foot = 2.0 * u + Vec3(0, 0, 0.34);
  std::vector<geo::ScenePrimitive> prims{beam, cylinder(foot, 0.1, 1.5)};
  EXPECT_EQ(columns_into_members(prims, std::vector<double>{0.05, 0.05}, kCos), 1);
  EXPECT_NEAR(prims[1].spec.placement.translation().z(), 0.15, 1e-12);
  EXPECT_NEAR(top_of(prims[1]), 1.84, 1e-12);  // the top stays
  EXPECT_NEAR(prims[1].spec.height, 1.69, 1e-12);
}

TEST(FitMembers, WhatIsNotAJointIsLeftAlone) {
  const std::vector<double> reach(2, 0.05);
  // A gap larger than the noise margin: 0.5 m of air above the column.
  std::vector<geo::ScenePrimitive> far{cylinder({0, 0, 0}, 0.15, 3.2),
                                       box({0, -0.1, 3.7}, {3, 0.2, 0.3})};
  EXPECT_EQ(columns_into_members(far, reach, kCos), 0);
  EXPECT_EQ(far[0].spec.height, 3.2);
  // A beam passing beside the column's axis, not over it.
  std::vector<geo::ScenePrimitive> beside{cylinder({0, 0.5, 0}, 0.15, 3.67),
                                          box({0, -0.1, 3.7}, {3, 0.2, 0.3})};
  EXPECT_EQ(columns_into_members(beside, reach, kCos), 0);
  // A beam ending a metre before the column.
  std::vector<geo::ScenePrimitive> before{cylinder({-1.5, 0, 0}, 0.15, 3.67),
                                          box({0, -0.1, 3.7}, {3, 0.2, 0.3})};
  EXPECT_EQ(columns_into_members(before, reach, kCos), 0);
  // A block, not a member (not twice as long as it is wide).
  std::vector<geo::ScenePrimitive> block{cylinder({0, 0, 0}, 0.15, 3.67),
                                         box({-0.5, -0.5, 3.7}, {1, 1, 0.6})};
  EXPECT_EQ(columns_into_members(block, reach, kCos), 0);
  // A drum, not a column (shorter than twice its width), under a beam.
  std::vector<geo::ScenePrimitive> drum{cylinder({0, 0, 3.1}, 0.15, 0.57),
                                        box({0, -0.1, 3.7}, {3, 0.2, 0.3})};
  EXPECT_EQ(columns_into_members(drum, reach, kCos), 0);
  // A beam along the column's own axis (a continuation, not a member it carries).
  std::vector<geo::ScenePrimitive> along{cylinder({0, 0, 0}, 0.15, 3.67),
                                         box({-0.1, -0.1, 3.7}, {0.2, 0.2, 3})};
  EXPECT_EQ(columns_into_members(along, reach, kCos), 0);
}

TEST(FitMembers, TheNearestMemberIsTakenAndEachMemberAsFitted) {
  // Two beams crossing above the column at 3.70 and 4.00 (one on the other): the lower one's
  // middle. A column under the column (stacked posts) is a continuation, not a member.
  std::vector<geo::ScenePrimitive> prims{
      cylinder({0, 0, 0}, 0.15, 3.67), box({-1.5, -0.1, 3.7}, {3, 0.2, 0.3}),
      box({-0.1, -1.5, 4.0}, {0.2, 3, 0.3}), cylinder({0, 0, -2}, 0.15, 1.98)};
  EXPECT_EQ(columns_into_members(prims, std::vector<double>(4, 0.05), kCos), 1);
  EXPECT_NEAR(top_of(prims[0]), 3.85, 1e-12);
  EXPECT_NEAR(prims[0].spec.placement.translation().z(), 0.0, 1e-12);
  EXPECT_NEAR(top_of(prims[3]), -0.02, 1e-12);
}

}  // namespace
}  // namespace csgtile::fit::detail
