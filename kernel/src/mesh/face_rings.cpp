#include "csgtile/kernel/face_rings.h"

#include <algorithm>
#include <memory>

#include "csgtile/kernel/explorer.h"

namespace csgtile::kernel {

// Wires are read through the face used Forward (so that "the face lies left of each edge,
// seen from the surface normal" holds) and reversed at the end when the solid uses the face
// Reversed.
std::optional<std::vector<std::vector<Vec3>>> planar_face_rings(const Shape& face,
                                                                const EdgePoints& edge_points) {
  std::vector<std::vector<Vec3>> rings;
  const Shape forward = face.oriented(Orientation::Forward);
  for (const Shape& wire : forward.children()) {
    std::vector<Shape> edges = wire.children();
    // Children of a Reversed wire are reversed one by one; their sequence must be too.
    if (wire.orientation() == Orientation::Reversed) std::reverse(edges.begin(), edges.end());
    std::vector<Vec3> ring;
    for (const Shape& edge : edges) {
      std::vector<Vec3> points = edge_points(edge);
      if (edge.orientation() == Orientation::Reversed) std::reverse(points.begin(), points.end());
      // Without its logical end: the next edge of the wire starts there.
      if (!points.empty()) ring.insert(ring.end(), points.begin(), points.end() - 1);
    }
    ring.erase(std::unique(ring.begin(), ring.end()), ring.end());
    while (ring.size() > 1 && ring.front() == ring.back()) ring.pop_back();
    if (ring.size() < 3) {
      if (rings.empty()) return std::nullopt;  // no exterior: nothing to draw
      continue;
    }
    if (face.orientation() == Orientation::Reversed) std::reverse(ring.begin(), ring.end());
    rings.push_back(std::move(ring));
  }
  if (rings.empty()) return std::nullopt;
  return rings;
}

EdgePoints mesh_edge_points(const Shape& root, const Mesh& mesh) {
  auto edges = std::make_shared<const ShapeIndex>(map_child_shapes(root, ShapeKind::Edge));
  return [edges, &mesh](const Shape& edge) {
    std::vector<Vec3> out;
    const std::size_t e = edges->find(edge);
    if (e < mesh.edge_vertices.size()) {
      for (std::uint32_t v : mesh.edge_vertices[e]) out.push_back(mesh.vertices[v]);
    }
    return out;
  };
}

}  // namespace csgtile::kernel
