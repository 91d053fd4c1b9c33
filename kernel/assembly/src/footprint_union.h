#pragma once
// The union of footprint polygons that tile a region edge to edge (a building's roof parts
// of one LoD1.3 level), in the plane: their shared edges cancel and what is left is walked into
// rings (footprint_union.cpp). The block model then fuses one prism per level and connected
// piece instead of one per roof part.

#include <optional>
#include <vector>

#include "csgtile/kernel/location.h"

namespace csgtile::assembly::detail {

/// A polygon: its outer ring and holes (either orientation).
struct FootprintPolygon {
  std::vector<kernel::Vec2> outer;
  std::vector<std::vector<kernel::Vec2>> holes;
};

/// The union of `polygons` when they meet only along whole edges or parts of edges (a vertex
/// of one lying on another's edge, within `tolerance`, splits that edge) and never overlap:
/// each connected piece an outer ring (counter-clockwise) with its holes (clockwise), collinear
/// and repeated vertices removed. nullopt when the polygons do not tile that way (an overlap,
/// a gap's edges not closing, two pieces meeting at a vertex only, a ring crossing itself, or
/// an area not kept to 1e-9 of the total): the caller keeps the polygons as they are.
/// Deterministic (input order).
std::optional<std::vector<FootprintPolygon>> union_of_tiles(
    const std::vector<FootprintPolygon>& polygons, double tolerance);

}  // namespace csgtile::assembly::detail
