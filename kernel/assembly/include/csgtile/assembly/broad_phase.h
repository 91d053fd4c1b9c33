#pragma once
/// \file
/// The kernel's broad phase (csgtile/kernel/broad_phase.h) on TBB: the assembly's candidate
/// pairs and the topology index's relations.

#include <span>
#include <vector>

#include "csgtile/kernel/broad_phase.h"

namespace csgtile::assembly {

/// The same sorted pairs as kernel::overlapping_boxes, whatever the number of threads: the
/// sweep's positions are cut into fixed blocks that run in parallel in the caller's TBB arena,
/// each block's pairs are kept apart, and the union is sorted.
std::vector<kernel::BoxPair> parallel_overlapping_boxes(std::span<const kernel::BoundingBox> boxes);

}  // namespace csgtile::assembly
