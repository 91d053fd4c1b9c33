// The fit's scale estimates (grid.cpp: spacing, reach, noise from a sample of neighbourhoods)
// and the torus candidate from samples (surface.cpp), on clouds with known answers.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

#include "fit_internal.h"

namespace csgtile::fit::detail {
namespace {

using kernel::Vec3;

std::vector<std::uint32_t> all(const std::vector<Vec3>& points) {
  std::vector<std::uint32_t> members(points.size());
  for (std::uint32_t i = 0; i < members.size(); ++i) members[i] = i;
  return members;
}

// A tilted plane sampled on a jittered 5 cm grid, `sigma` of Gaussian noise along its normal.
std::vector<Vec3> noisy_plane(double sigma, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, sigma);
  std::uniform_real_distribution<double> jitter(-0.01, 0.01);
  const Vec3 normal = Vec3(0.2, -0.3, 1.0).normalized();
  const Vec3 e1 = normal.cross(Vec3::UnitX()).normalized();
  const Vec3 e2 = normal.cross(e1);
  std::vector<Vec3> points;
  for (int i = 0; i < 120; ++i) {
    for (int j = 0; j < 120; ++j) {
      const double u = 0.05 * i + jitter(rng), v = 0.05 * j + jitter(rng);
      points.push_back(Vec3(10.0, -4.0, 2.0) + u * e1 + v * e2 + noise(rng) * normal);
    }
  }
  return points;
}

TEST(FitEstimates, NoiseOfANoisyPlaneIsItsSigma) {
  constexpr double kSigma = 0.01;
  const auto points = noisy_plane(kSigma, 7);
  const auto members = all(points);
  // A neighbourhood of 17 points about its own least-squares plane keeps 14 of 17 degrees of
  // freedom of the noise: its RMS is about σ·√(14/17) ≈ 0.91 σ, with a spread over the sample.
  const double median = estimate_noise(points, members, 0.5);
  EXPECT_GT(median, 0.75 * kSigma);
  EXPECT_LT(median, 1.05 * kSigma);
  // Exact points: no noise at any quantile.
  const auto exact = noisy_plane(0.0, 7);
  EXPECT_LT(estimate_noise(exact, all(exact), 0.95), 1e-9);
}

TEST(FitEstimates, NoiseIsTheQuantileOfTheSampledNeighbourhoods) {
  // estimate_noise asks for the plane residuals alone; the sample that also holds the quadric
  // residuals (for the RANSAC) gives the same figures at every quantile.
  const auto points = noisy_plane(0.02, 11);
  const auto members = all(points);
  const NeighbourSample sample(points, members, true);
  for (const double q : {0.05, 0.5, 0.95}) {
    EXPECT_EQ(estimate_noise(points, members, q), sample.noise(q)) << q;
  }
}

TEST(FitEstimates, ReachOfAVolumeFilledCloudMatchesTheNearestNeighbours) {
  // Points filling a cube: the search starts from the spacing of a surface over the box, far
  // too small for a volume, so its first attempts find under half of their samples and are
  // given up for a cell twice as wide. The reach found is the 16th neighbour's distance.
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> coordinate(0.0, 2.0);
  std::vector<Vec3> points;
  for (int i = 0; i < 4000; ++i) {
    points.emplace_back(coordinate(rng), coordinate(rng), coordinate(rng));
  }
  const auto members = all(points);
  const double reach = neighbour_reach(points, members, 0.5);
  // Brute force over every point: the median distance to its 16th nearest.
  std::vector<double> kth;
  for (const Vec3& p : points) {
    std::vector<double> d;
    for (const Vec3& q : points) d.push_back((q - p).norm());
    std::nth_element(d.begin(), d.begin() + 16, d.end());  // d[0] is the point itself
    kth.push_back(d[16]);
  }
  std::nth_element(kth.begin(), kth.begin() + static_cast<std::ptrdiff_t>(kth.size() / 2),
                   kth.end());
  const double expected = kth[kth.size() / 2];
  EXPECT_NEAR(reach, expected, 0.05 * expected);
}

// Exact points and normals on a torus of major radius R and minor radius r about `axis`
// through `centre`.
void torus_samples(const Vec3& centre, const Vec3& axis, double major, double minor, int count,
                   std::vector<Vec3>& p, std::vector<Vec3>& n) {
  const Vec3 z = axis.normalized();
  const Vec3 x = z.cross(Vec3::UnitX()).normalized();
  const Vec3 y = z.cross(x);
  for (int k = 0; k < count; ++k) {
    const double u = 0.61 * k + 0.2, v = 1.37 * k + 0.5;  // spread over both angles
    const Vec3 radial = std::cos(u) * x + std::sin(u) * y;
    const Vec3 normal = std::cos(v) * radial + std::sin(v) * z;
    p.push_back(centre + major * radial + minor * normal);
    n.push_back(normal);
  }
}

TEST(FitEstimates, TorusFromAFewSamplesAndFromManyGivesItsRadii) {
  // A RANSAC draw's seven samples (the decomposition on the stack) and forty (on the heap).
  const Vec3 centre(3.0, -2.0, 1.5), axis = Vec3(0.3, 0.1, 1.0).normalized();
  for (const int count : {7, 40}) {
    std::vector<Vec3> p, n;
    torus_samples(centre, axis, 2.0, 0.5, count, p, n);
    const auto torus = torus_from_samples(p, n, 100.0);
    ASSERT_TRUE(torus.has_value()) << count;
    EXPECT_EQ(torus->type, ShapeType::Torus);
    EXPECT_NEAR(torus->radius, 2.0, 1e-9) << count;
    EXPECT_NEAR(torus->radius2, 0.5, 1e-9) << count;
    EXPECT_NEAR(std::abs(torus->axis.dot(axis)), 1.0, 1e-12) << count;
    EXPECT_NEAR((torus->point - centre).norm(), 0.0, 1e-9) << count;
  }
}

}  // namespace
}  // namespace csgtile::fit::detail
