#pragma once
// Groups of solids that can touch: connected components of the overlap graph of their
// bounding boxes (enlarged by the tolerance), found by a sweep along x.

#include <cstddef>
#include <vector>

#include "csgtile/kernel/shape.h"

namespace csgtile::kernel::detail {

/// Components as lists of input indices, each list ascending, lists ordered by their
/// smallest member: deterministic, input order preserved.
std::vector<std::vector<std::size_t>> fuse_groups(const std::vector<Shape>& shapes,
                                                  double tolerance);

}  // namespace csgtile::kernel::detail
