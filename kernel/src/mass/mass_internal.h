#pragma once
// Mass properties for the kernel's own decisions (private to the kernel).

#include "csgtile/kernel/shape.h"

namespace csgtile::kernel::detail {

/// The volume of mass_properties(shape) alone, without area, centroid and bounding box: what
/// the Boolean engine and the checker need to orient shells and solids. The same boundary
/// integral, with the inner (u) integral in closed form on planes and kept per u on cylinders
/// (the faces of city models): equal to mass_properties' volume up to rounding (1e-12
/// relative in tests/unit/kernel/boolean_speed_test.cpp), several times faster.
double solid_volume(const Shape& shape);

}  // namespace csgtile::kernel::detail
