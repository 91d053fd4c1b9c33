#pragma once
/// \file
/// A seeded synthetic city for assembly tests and benchmarks: lots on a grid of blocks
/// (4 × 4 lots, every other block turned by a random yaw), each with a building — a box or
/// an L-shaped extrusion, 5–25 m tall — and sometimes a wing box reaching into it, a roof box
/// standing on it (touching), a column through its corner, or a column 5–30 cm off its wall
/// (near miss). About a third of the primitives overlap or touch a neighbour.

#include <cstdint>
#include <vector>

#include "csgtile/kernel/primitives.h"

namespace csgtile::test {

struct CityOptions {
  bool axis_aligned_boxes_only = false;  ///< no yaw, no extrusions, no columns
  double lot = 14.0;                     ///< lot pitch, metres
};

/// Exactly n primitives (n ≥ 0), deterministic for a seed.
std::vector<kernel::PrimitiveSpec> random_city(int n, std::uint64_t seed,
                                               const CityOptions& options = {});

/// The Boolean benchmarks' city block: exactly n primitives (n ≥ 0) on a grid of 12 m lots,
/// each an axis-aligned box 6–9 m wide and 5–25 m tall, 30 % with a wing box reaching into
/// the next lot (overlapping), 20 % with a column at the box's corner. Deterministic for a seed.
std::vector<kernel::PrimitiveSpec> city_block(int n, std::uint64_t seed);

}  // namespace csgtile::test
