// A curved primitive must show its curvature (support.cpp, flat_strips): the points a cylinder
// or cone was fitted to, cut into pieces around its axis, must not be explained as well by one
// plane per piece.

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "fit_internal.h"

namespace csgtile::fit::detail {
namespace {

using kernel::PrimitiveSpec;
using kernel::PrimitiveType;
using kernel::Vec3;

constexpr double kSigma = 0.01;  // 1 cm of noise, as a terrestrial scan of a frame
constexpr double kCell = 0.05;

std::vector<std::uint32_t> all(const std::vector<Vec3>& points) {
  std::vector<std::uint32_t> members(points.size());
  for (std::uint32_t i = 0; i < members.size(); ++i) members[i] = i;
  return members;
}

PrimitiveSpec along(PrimitiveType type, const Vec3& origin, const Vec3& axis, double r1, double r2,
                    double h) {
  const Vec3 z = axis.normalized();
  const Vec3 x = (std::abs(z.z()) < 0.9 ? Vec3::UnitZ() : Vec3::UnitX()).cross(z).normalized();
  kernel::Matrix34 q;
  q.col(0) = x;
  q.col(1) = z.cross(x);
  q.col(2) = z;
  q.col(3) = origin;
  PrimitiveSpec spec;
  spec.type = type;
  spec.radius = r1;
  spec.radius2 = r2;
  spec.height = h;
  spec.placement = kernel::Location::from_matrix(q).value();
  return spec;
}

// Points on the cylinder of radius r about the z axis, over the angles [a0, a1], z in [0, h].
std::vector<Vec3> arc(double r, double a0, double a1, double h, int count, std::mt19937& rng) {
  std::uniform_real_distribution<double> angle(a0, a1), height(0.0, h);
  std::normal_distribution<double> noise(0.0, kSigma);
  std::vector<Vec3> points;
  for (int i = 0; i < count; ++i) {
    const double a = angle(rng), rr = r + noise(rng);
    points.emplace_back(rr * std::cos(a), rr * std::sin(a), height(rng));
  }
  return points;
}

// The top faces of two beams meeting at right angles at a node (along +x and +y from the
// origin, 0.2 m wide, 2 m long, at z = 0) lie on the 45° cone whose axis bisects them: the
// flat strips of a frame's node, not a cone.
TEST(FitSupport, ConeOverTwoBeamFacesIsFlatStrips) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> length(0.2, 2.0), width(-0.1, 0.1);
  std::normal_distribution<double> noise(0.0, kSigma);
  std::vector<Vec3> points;
  for (int i = 0; i < 300; ++i) points.emplace_back(length(rng), width(rng), noise(rng));
  for (int i = 0; i < 300; ++i) points.emplace_back(width(rng), length(rng), noise(rng));
  const PrimitiveSpec cone =
      along(PrimitiveType::Cone, Vec3::Zero(), Vec3(1, 1, 0), 0.01, 1.5, 1.49);
  const std::string why = flat_strips(cone, points, all(points), kSigma, kCell);
  EXPECT_NE(why.find("curvature unseen"), std::string::npos) << why;
}

// A narrow strip of a wide cylinder bends by less than the noise: a plane.
TEST(FitSupport, NarrowStripOfAWideCylinderIsFlat) {
  std::mt19937 rng(8);
  const double r = 3.0;
  const std::vector<Vec3> points = arc(r, 0.0, 0.2 / r, 2.0, 400, rng);
  const PrimitiveSpec cylinder =
      along(PrimitiveType::Cylinder, Vec3::Zero(), Vec3::UnitZ(), r, 0.0, 2.0);
  EXPECT_FALSE(flat_strips(cylinder, points, all(points), kSigma, kCell).empty());
}

// A column seen from one side over 90° (or seen all round, or on two opposite sides) shows
// its curvature; so does a cone seen over half its turn.
TEST(FitSupport, ColumnsAndConesSeenInPartShowTheirCurvature) {
  std::mt19937 rng(9);
  const PrimitiveSpec column =
      along(PrimitiveType::Cylinder, Vec3::Zero(), Vec3::UnitZ(), 0.15, 0.0, 3.0);
  const std::vector<Vec3> quarter = arc(0.15, 0.0, 0.5 * std::numbers::pi, 3.0, 400, rng);
  EXPECT_EQ(flat_strips(column, quarter, all(quarter), kSigma, kCell), "");
  const std::vector<Vec3> ring = arc(0.15, -std::numbers::pi, std::numbers::pi, 3.0, 400, rng);
  EXPECT_EQ(flat_strips(column, ring, all(ring), kSigma, kCell), "");
  std::vector<Vec3> sides = arc(0.15, -0.6, 0.6, 3.0, 200, rng);
  const std::vector<Vec3> back = arc(0.15, 2.5, 3.7, 3.0, 200, rng);
  sides.insert(sides.end(), back.begin(), back.end());
  EXPECT_EQ(flat_strips(column, sides, all(sides), kSigma, kCell), "");

  // A cone from radius 1 (z = 0) to 0.5 (z = 1), seen over half its turn.
  std::uniform_real_distribution<double> angle(0.0, std::numbers::pi), t(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, kSigma);
  std::vector<Vec3> cone_points;
  for (int i = 0; i < 400; ++i) {
    const double a = angle(rng), z = t(rng), r = 1.0 - 0.5 * z + noise(rng);
    cone_points.emplace_back(r * std::cos(a), r * std::sin(a), z);
  }
  const PrimitiveSpec cone = along(PrimitiveType::Cone, Vec3::Zero(), Vec3::UnitZ(), 1.0, 0.5, 1.0);
  EXPECT_EQ(flat_strips(cone, cone_points, all(cone_points), kSigma, kCell), "");
  // Boxes and spheres are not asked.
  PrimitiveSpec box;
  EXPECT_EQ(flat_strips(box, quarter, all(quarter), kSigma, kCell), "");
}

}  // namespace
}  // namespace csgtile::fit::detail
