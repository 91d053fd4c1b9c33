#pragma once
// Point contacts between the parts of a roof partition (part_contacts.cpp): two parts whose
// polygons meet at one vertex only, with a third part wedged between them there, make a
// vertical edge that two solids share alone wherever both stand and the third does not (its
// base higher or its roof lower) — an edge of four faces, which no valid solid has.

#include <vector>

#include "fit_internal.h"

namespace csgtile::fit::detail {

/// For each vertex where two extrusion parts of `parts` meet at that vertex only, the other
/// parts at the vertex are extended over the heights both stand at there: a base lowered to
/// the higher of the two bases (under the terrain's level, unseen), a flat roof raised to the
/// lower of their roofs at the vertex when that is at most `max_raise` higher (a step the fit
/// cannot tell from noise). Where a part between them still stands lower there (a storey
/// lower, or a tilted roof), the corner of one of the two (the lower at the vertex, whose
/// corner is convex) is cut off by `corner` along its edges, so that they no longer meet.
/// Clip planes are kept in place. Returns the number of parts changed.
int close_point_contacts(std::vector<Proposal>& parts, double max_raise, double corner);

}  // namespace csgtile::fit::detail
