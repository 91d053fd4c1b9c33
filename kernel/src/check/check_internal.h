#pragma once
// The validity checker with solid volumes its caller already holds (private to the kernel).

#include <utility>
#include <vector>

#include "csgtile/kernel/check.h"

namespace csgtile::kernel::detail {

/// check_shape(shape), where each (solid, volume) of `known` gives detail::solid_volume(solid)
/// of a solid of `shape` (equal as a Shape: body, location, orientation), computed by the
/// caller: the checker's orientation test uses that number instead of integrating the solid
/// again. The same checks, the same report. Solids not listed are integrated as usual.
CheckReport check_shape_with_volumes(const Shape& shape,
                                     const std::vector<std::pair<Shape, double>>& known);

}  // namespace csgtile::kernel::detail
