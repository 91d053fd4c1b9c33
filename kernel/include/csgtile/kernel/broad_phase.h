#pragma once
/// \file
/// The broad phase: which boxes of a set meet. One sweep for every caller (the n-ary fuse's
/// groups, the assembly's candidate pairs, the topology index's relations).

#include <cstddef>
#include <span>
#include <utility>
#include <vector>

#include "csgtile/kernel/bounding_box.h"

namespace csgtile::kernel {

/// Index pairs (i < j) of the boxes that intersect (closed boxes; an empty box meets nothing),
/// sorted. Boxes are used as given: enlarge them by the tolerance first. A sweep along x after
/// sorting by the boxes' minimum x: O(n log n + the pairs whose x-intervals overlap).
std::vector<std::pair<std::size_t, std::size_t>> overlapping_boxes(
    std::span<const BoundingBox> boxes);

}  // namespace csgtile::kernel
