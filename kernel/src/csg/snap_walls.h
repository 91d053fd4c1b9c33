#pragma once
// The fuzzy snap's last step: the side walls of parallel extrusions made to share their
// vertices (kernel/snap.h, step 6).

#include <vector>

#include "csgtile/kernel/primitives.h"
#include "csgtile/kernel/snap.h"

namespace csgtile::kernel::detail {

/// For every group of extrusions whose axes are one direction (or opposite; steps 1 and 2 make them
/// so), seen along that direction: each profile vertex within `distance` of a vertex of an earlier
/// extrusion becomes that vertex, then each vertex within `distance` of another extrusion's edge
/// (four distances or more from its ends and from the vertices inserted there) is inserted into it,
/// where the two extrusions' heights overlap. A wall fitted a few millimetres off its neighbour's
/// corner then runs through the corner instead of leaving a sliver the exact Booleans would keep (a
/// slot millimetres wide, pinched to an edge at its end: a non-manifold solid). An extrusion whose
/// rings would no longer be simple keeps its own profile. Counts in `counts.walls_shared` and
/// `counts.max_move`. Deterministic (input order).
void share_extrusion_walls(std::vector<PrimitiveSpec>& primitives, double distance,
                           SnapReport& counts);

}  // namespace csgtile::kernel::detail
