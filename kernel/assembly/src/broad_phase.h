#pragma once
// Broad phase: pairs of boxes that overlap, by a sweep along x.

#include <cstddef>
#include <utility>
#include <vector>

#include "csgtile/kernel/bounding_box.h"

namespace csgtile::assembly::detail {

/// Index pairs (i < j) of boxes that intersect, sorted. Boxes are used as given (enlarge
/// them by the tolerance first). O(n log n + pairs + sweep overlap in x).
std::vector<std::pair<int, int>> overlapping_boxes(const std::vector<kernel::BoundingBox>& boxes);

}  // namespace csgtile::assembly::detail
