#pragma once
// Columns into the members they carry (members.cpp, issue #21 item 1 "its ends where the
// points stop or where it enters another member"): a column's top hidden among the beams it
// carries shows the scan no surface, so its fit stops a few centimetres below them, and the
// frame falls apart into loose columns. Fitted in a region of its own (its points not
// connected to the frame's), the column cannot be joined there: this runs over the whole fit.

#include <span>
#include <vector>

#include "csgtile/geo/scene.h"

namespace csgtile::fit::detail {

/// Each column of `primitives` (a cylinder without clips, at least twice as long as it is
/// wide) whose end stops short of a member crossing its axis (a box at least twice as long as
/// it is wide, or another such cylinder, its axis across the column's within the angle whose
/// cosine is `cos_tol`, the column's axis through its section) by at most `reach` (per
/// primitive: its region's noise margin) beyond the member's near side goes on to that
/// member's middle, as a frame's members meet. Its coverage shrinks with its grown area; its
/// other quality figures are those of its points. Members are taken as they were fitted (no
/// order effects). Returns how many ends moved.
int columns_into_members(std::vector<geo::ScenePrimitive>& primitives,
                         std::span<const double> reach, double cos_tol);

/// The noise margin of a region's members (how far short of another member an end may stop and
/// still meet it), from the region's RANSAC epsilon and cluster epsilon, as the region's own
/// join of members takes it.
double member_reach(double epsilon, double cluster_epsilon);

}  // namespace csgtile::fit::detail
