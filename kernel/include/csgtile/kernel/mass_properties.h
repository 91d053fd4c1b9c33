#pragma once
/// \file
/// Volume, surface area, centroid and bounding box of shapes.

#include "csgtile/kernel/bounding_box.h"
#include "csgtile/kernel/shape.h"

namespace csgtile::kernel {

struct MassProperties {
  double volume = 0.0;           ///< signed sum over the faces (positive for valid solids)
  double area = 0.0;             ///< total area of the faces
  Vec3 centroid = Vec3::Zero();  ///< of the volume (bounding-box centre when the volume is 0)
  BoundingBox bounds;            ///< exact for primitives; conservative for trimmed curved faces
};

/// Integrates over every face of `shape` (located and oriented as seen through it): the
/// volume by the divergence theorem V = ⅓∮ p·n dA, area ∮ dA, first moments ½∮ p_i² n_i dA.
/// Each face integral is reduced by Green's theorem to its boundary in the (u, v) plane
/// (through the faces' pcurves) and evaluated with composite 16-point Gauss–Legendre
/// panels no wider than π/4 in angular parameters (on planes, the inner integral in closed
/// form), so results are exact to rounding for the primitives (closed forms matched to 1e-12
/// relative in tests).
/// Shapes without faces give zeros. O(edges).
MassProperties mass_properties(const Shape& shape);

/// mass_properties(shape).volume, the same integral to the last bit, without the area,
/// centroid and bounding box.
double shape_volume(const Shape& shape);

/// Exact bounding box (see MassProperties::bounds).
BoundingBox bounding_box(const Shape& shape);

}  // namespace csgtile::kernel
