#pragma once
// A primitive prepared for ray casting: its placement inverted, its local bounds, and the
// boundary pieces of extrusions and revolutions listed once, so that each ray only solves.

#include <optional>
#include <vector>

#include "csgtile/geo/synth.h"
#include "csgtile/kernel/bounding_box.h"
#include "csgtile/kernel/primitives.h"

namespace csgtile::geo::detail {

struct PreparedPrimitive {
  kernel::PrimitiveSpec spec;
  Eigen::Matrix3d rotation_transposed;  ///< R^T: world directions to local
  double scale = 1.0;
  kernel::Vec3 translation = kernel::Vec3::Zero();
  kernel::BoundingBox local_bounds;
  kernel::BoundingBox world_bounds;
  kernel::Vec3 local_center = kernel::Vec3::Zero();  ///< rays restart near it (see hit)
  double slack = 0.0;  ///< how far outside a face's limits a crossing still counts (local units)
  bool partial_turn = false;  ///< revolution with angle < 2π (has end faces)
};

PreparedPrimitive prepare_primitive(const kernel::PrimitiveSpec& spec);

/// First crossing with t in (t_min, t_max] (world units, |direction| = 1). A primitive's
/// clips are not cast against (the simulator scans plain primitives).
std::optional<RayHit> hit_primitive(const PreparedPrimitive& p, const kernel::Vec3& origin,
                                    const kernel::Vec3& direction, double t_min, double t_max);

/// Whether `point` (world) lies in the solid, its clips honoured.
bool primitive_contains(const PreparedPrimitive& p, const kernel::Vec3& point);

/// Even-odd point-in-polygon over the rings of an extrusion's section (profile and holes) or a
/// revolution's profile: inside an odd number of them (kernel::inside_ring, polygon2d.h).
bool inside_rings(const PreparedPrimitive& p, const kernel::Vec2& q);

}  // namespace csgtile::geo::detail
