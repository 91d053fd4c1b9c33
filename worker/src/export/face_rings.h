#pragma once
// Boundary rings of planar faces, shared by the exporters that write faces as polygons (the
// topology index's objects layer, the CityJSON sequence).

#include <functional>
#include <optional>
#include <vector>

#include "csgtile/kernel/shape.h"

namespace csgtile::worker::detail {

/// Points along an edge from the start to the end of its curve's parameter range (empty for a
/// degenerate edge). Neighbouring faces must get the same points for an edge, so that their
/// rings meet exactly.
using EdgePoints = std::function<std::vector<kernel::Vec3>(const kernel::Shape& edge)>;

/// Rings of a planar face from its wires, exterior first, counter-clockwise seen from the side
/// the face's use marks as outward (holes clockwise). Rings are open (the first point is not
/// repeated) and have no consecutive repeated points; hole wires with fewer than three points
/// are left out. nullopt when the exterior has fewer than three points.
std::optional<std::vector<std::vector<kernel::Vec3>>> planar_face_rings(
    const kernel::Shape& face, const EdgePoints& edge_points);

}  // namespace csgtile::worker::detail
