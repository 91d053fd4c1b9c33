// The kernel's root finders (csgtile/kernel/polynomial.h): the Booleans' line–surface
// intersections and the scan simulator's ray casts both rest on them.

#include "csgtile/kernel/polynomial.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <vector>

namespace csgtile::kernel {
namespace {

TEST(Polynomial, RootsAreFoundAscendingAndMultipleOnesFlagged) {
  // (x − 1)(x − 2)(x − 3)(x − 4) = x⁴ − 10x³ + 35x² − 50x + 24.
  const double simple[] = {24, -50, 35, -10, 1};
  std::vector<PolynomialRoot> roots;
  polynomial_roots(simple, 4, -10, 10, roots);
  ASSERT_EQ(roots.size(), 4u);
  for (int i = 0; i < 4; ++i) {
    EXPECT_NEAR(roots[static_cast<std::size_t>(i)].x, i + 1.0, 1e-12);
    EXPECT_FALSE(roots[static_cast<std::size_t>(i)].multiple);
  }
  // (x − 1)²(x + 2)(x − 3) = x⁴ − 3x³ − 3x² + 11x − 6.
  const double doubled[] = {-6, 11, -3, -3, 1};
  roots.clear();
  polynomial_roots(doubled, 4, -10, 10, roots);
  ASSERT_EQ(roots.size(), 3u);
  EXPECT_NEAR(roots[0].x, -2.0, 1e-12);
  EXPECT_NEAR(roots[1].x, 1.0, 1e-7);
  EXPECT_TRUE(roots[1].multiple);
  EXPECT_NEAR(roots[2].x, 3.0, 1e-12);
  // Restricted to an interval; appended after what `out` held.
  polynomial_roots(simple, 4, 1.5, 3.5, roots);
  ASSERT_EQ(roots.size(), 5u);
  EXPECT_NEAR(roots[3].x, 2.0, 1e-12);
  EXPECT_NEAR(roots[4].x, 3.0, 1e-12);
}

TEST(Polynomial, TwoRootsCloserThanTheNoiseComeBackAsOneMultipleRoot) {
  // (x − 1)(x − 1 − 1e-12): the pair cannot be told apart from a double root in doubles.
  const double d = 1e-12;
  const double close[] = {1.0 + d, -(2.0 + d), 1.0};
  std::vector<PolynomialRoot> roots;
  polynomial_roots(close, 2, 0.0, 2.0, roots);
  ASSERT_EQ(roots.size(), 1u);
  EXPECT_TRUE(roots[0].multiple);
  EXPECT_NEAR(roots[0].x, 1.0, 1e-6);
}

TEST(Polynomial, QuadraticIsFreeOfCancellationAndFlagsTangency) {
  std::array<double, 2> r{};
  bool multiple = true;
  // x² − 1e8·x + 1: the small root 1e-8 is lost by the textbook formula's subtraction.
  ASSERT_EQ(solve_quadratic(1.0, -0.5e8, 1.0, 1.0, r, multiple), 2);
  EXPECT_FALSE(multiple);
  EXPECT_NEAR(r[0], 1e-8, 1e-22);
  EXPECT_NEAR(r[1], 1e8, 1e-6);
  // (x − 3)² within rounding: one root, flagged; a clear miss: none.
  ASSERT_EQ(solve_quadratic(1.0, -3.0, 9.0 + 1e-15, 9.0, r, multiple), 1);
  EXPECT_TRUE(multiple);
  EXPECT_DOUBLE_EQ(r[0], 3.0);
  EXPECT_EQ(solve_quadratic(1.0, 0.0, 1.0, 1.0, r, multiple), 0);
  // Linear when a = 0: 2·2·t + 8 = 0.
  ASSERT_EQ(solve_quadratic(0.0, 2.0, 8.0, 8.0, r, multiple), 1);
  EXPECT_DOUBLE_EQ(r[0], -2.0);
}

}  // namespace
}  // namespace csgtile::kernel
