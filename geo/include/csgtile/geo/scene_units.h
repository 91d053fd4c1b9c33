#pragma once
/// \file
/// Scene primitives from one length unit to another. The fit works in metres whatever the
/// tile's CRS counts in (every fit option is a length in metres): a tile in feet is fitted in
/// metres and its primitives are given back in feet. Horizontal and vertical units may differ
/// (a CRS in metres with heights in US survey feet), so the map is diag(h, h, v).

#include "csgtile/geo/scene.h"
#include "csgtile/kernel/result.h"

namespace csgtile::geo {

/// The map p → (h·x, h·y, v·z) of a frame's coordinates.
struct UnitScale {
  double horizontal = 1.0;
  double vertical = 1.0;
  bool identity() const { return horizontal == 1.0 && vertical == 1.0; }
  bool uniform() const { return horizontal == vertical; }
  /// The inverse map.
  UnitScale inverse() const { return {1.0 / horizontal, 1.0 / vertical}; }
  kernel::Vec3 apply(const kernel::Vec3& p) const {
    return {horizontal * p.x(), horizontal * p.y(), vertical * p.z()};
  }
};

/// `primitive` mapped by `scale` (placement translation, sizes, radii, heights, profiles,
/// clip planes; the quality's rms and sigma by the horizontal factor). Exact for every type
/// when the scale is uniform. Otherwise the primitive must keep its shape under the map: its
/// placement keeps the local z axis vertical (a rotation about z, possibly upside down) and
/// it is a box, cylinder, cone, extrusion or revolution (a building's parts, a column); a
/// sphere, a torus or a tilted primitive would become an ellipsoid or a sheared solid, and is
/// Unsupported naming why. InvalidArgument for a factor that is not positive and finite.
kernel::Result<ScenePrimitive> scaled_primitive(const ScenePrimitive& primitive,
                                                const UnitScale& scale);

}  // namespace csgtile::geo
