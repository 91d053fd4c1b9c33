#pragma once
/// \file
/// Seeded random directions, points, frames and similarities for geometry tests
/// (std::mt19937, as the curve and surface tests draw them).

#include <gtest/gtest.h>

#include <random>

#include "csgtile/kernel/frame.h"
#include "csgtile/kernel/location.h"

namespace csgtile::test {

/// A unit vector, uniformly distributed on the sphere.
kernel::Vec3 random_unit(std::mt19937& rng);
/// A point in the cube [-extent, extent]³.
kernel::Vec3 random_point(std::mt19937& rng, double extent);
/// A frame with its origin in [-5, 5]³ and random axes.
kernel::Frame random_frame(std::mt19937& rng);
/// A random proper similarity (scale in [0.3, 3]) built through Location::from_matrix.
kernel::Location random_similarity(std::mt19937& rng);
/// EXPECT that |a − b| <= tolerance, printing both.
void expect_near(const kernel::Vec3& a, const kernel::Vec3& b, double tolerance);

}  // namespace csgtile::test
