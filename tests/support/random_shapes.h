#pragma once
/// \file
/// Seeded generators of random primitives and placements for property tests.

#include <random>

#include "csgtile/kernel/primitives.h"

namespace csgtile::test {

/// A random proper rotation × scale in [0.2, 5] + translation in [-100, 100]³.
kernel::Location random_similarity(std::mt19937_64& rng);

/// A random primitive spec of the given type with sizes in [0.1, 10] and identity placement.
kernel::PrimitiveSpec random_primitive(std::mt19937_64& rng, kernel::PrimitiveType type);

}  // namespace csgtile::test
