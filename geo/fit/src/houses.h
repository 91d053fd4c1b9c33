#pragma once
// Houses of a block (houses.cpp, issue #18 item 2): without a footprint, one region of
// building points is often a whole block of adjoining houses. Its roof partition says where
// one house ends: two parts whose roofs meet along their boundary (a ridge, a hip, a valley,
// one roof over both) are one house; a height step between them (a wall above the lower roof)
// separates two. What is too small, too thin or too enclosed to be a house of its own (a
// dormer, a chimney, a parapet, a structure on a flat roof) joins the house it shares most of
// its boundary with.

#include <vector>

namespace csgtile::fit::detail {

/// One part of a partition: its area, the length of its boundary, and of the part of that
/// boundary on the outside (a facade, a courtyard's wall, or a wall the neighbour beyond it
/// does not share: one part's base above the other's roof).
struct HousePart {
  double area = 0.0;
  double perimeter = 0.0;
  double outside = 0.0;
};

/// The boundary between parts `a` < `b` where they share a wall: its length, its number of
/// cell edges, and how many of those are continuous (the two roofs at one height there,
/// within a step plus what the difference of their slopes allows over a cell).
struct PartBoundary {
  int a = 0, b = 0;
  double length = 0.0;
  long long edges = 0;
  long long continuous = 0;
};

/// What a house must be: at least `min_area`, at least `min_width` wide (twice its area over
/// its perimeter), and with at least `min_outside` of its perimeter on the outside.
struct HouseRules {
  double min_area = 25.0;
  double min_width = 1.5;
  double min_outside = 0.1;
};

/// Per part, its house. Parts joined by a boundary at least four fifths continuous (two slopes
/// of different pitch meeting at the eaves differ along the rest of their boundary), whose
/// continuous edges are at least `min_width` long (not a corner), are one house. Then a house
/// that breaks a rule joins the neighbouring house with the longest boundary to it, the
/// smallest such house first (ties, of area or of length, to the lower index), until every
/// house with a neighbour keeps the rules. Houses are numbered 0, 1, ... in the order of their
/// first part. Deterministic.
std::vector<int> group_houses(const std::vector<HousePart>& parts,
                              const std::vector<PartBoundary>& boundaries, const HouseRules& rules);

}  // namespace csgtile::fit::detail
