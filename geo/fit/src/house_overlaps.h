#pragma once
// Houses that overlap (house_overlaps.cpp): a building seen from the air is often clustered
// into several regions of points (a roof a storey above its neighbour, no wall points between
// them), each region's houses derived from its own points. Their solids may overlap where the
// outlines do; two buildings never overlap, so such houses are one.

#include <vector>

#include "csgtile/geo/scene.h"

namespace csgtile::fit::detail {

/// Joins the houses of `primitives` whose solids overlap by more than `margin` in each
/// direction (sampled: a point inside both): the later house takes the earlier one's name (in
/// the order of their first primitive); a region without houses (`region` per primitive, its
/// primitives' house "") that overlaps a house joins it as a whole. Primitives of a footprint
/// (building set) take no part. Deterministic.
void join_overlapping_houses(std::vector<geo::ScenePrimitive>& primitives,
                             const std::vector<int>& region, double margin);

}  // namespace csgtile::fit::detail
