#pragma once
// Splitting a face along the section edges that lie in it: the (u, v)-plane arrangement of
// its boundary uses and section edges, traced into the boundary cycles of its pieces.

#include "boolean/model.h"

namespace csgtile::kernel::detail {

/// A piece of a face: loops in the face's (u, v) plane, outer loop first (counter-clockwise),
/// then holes (clockwise).
struct Region {
  std::vector<BLoop> loops;
};

/// Pieces of `face` cut by `face.extra` (each section edge bounds a piece on both sides;
/// section edges with a free end are ignored). Error: InvalidShape when a cycle cannot be
/// closed or a hole has no piece around it.
Result<std::vector<Region>> split_face(const BModel& m, const BFace& face);

/// The signed area of a loop in (u, v): of the polygon of its sampled pcurves (ring_area).
double loop_area(const BModel& m, const BLoop& loop);

}  // namespace csgtile::kernel::detail
