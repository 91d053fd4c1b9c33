#pragma once
/// \file
/// Boundary rings of planar faces as point loops: what exporters write as polygons and what
/// footprints are made of. The points of each edge come from the caller (typically a
/// tessellation's edge points), so that neighbouring faces' rings meet exactly.

#include <functional>
#include <optional>
#include <vector>

#include "csgtile/kernel/shape.h"
#include "csgtile/kernel/tessellation.h"

namespace csgtile::kernel {

/// Points along an edge from the start to the end of its curve's parameter range (empty for a
/// degenerate edge).
using EdgePoints = std::function<std::vector<Vec3>(const Shape& edge)>;

/// Rings of a planar face from its wires, exterior first, counter-clockwise seen from the side
/// the face's use marks as outward (holes clockwise). Rings are open (the first point is not
/// repeated) and have no consecutive repeated points; hole wires with fewer than three points
/// are left out. nullopt when the exterior has fewer than three points.
std::optional<std::vector<std::vector<Vec3>>> planar_face_rings(const Shape& face,
                                                                const EdgePoints& edge_points);

/// The edge points of `mesh`, a tessellation of `root`: an edge of `root` (as its explorers
/// give it) maps to its mesh points; an edge the mesh does not know gets none. The returned
/// function refers to `root` and `mesh`, which must outlive it.
EdgePoints mesh_edge_points(const Shape& root, const Mesh& mesh);

}  // namespace csgtile::kernel
