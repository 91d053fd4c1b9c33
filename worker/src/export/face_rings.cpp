#include "export/face_rings.h"

#include <algorithm>

namespace csgtile::worker::detail {

// Wires are read through the face used Forward (so that "the face lies left of each edge,
// seen from the surface normal" holds) and reversed at the end when the solid uses the face
// Reversed.
std::optional<std::vector<std::vector<kernel::Vec3>>> planar_face_rings(
    const kernel::Shape& face, const EdgePoints& edge_points) {
  std::vector<std::vector<kernel::Vec3>> rings;
  const kernel::Shape forward = face.oriented(kernel::Orientation::Forward);
  for (const kernel::Shape& wire : forward.children()) {
    std::vector<kernel::Shape> edges = wire.children();
    // Children of a Reversed wire are reversed one by one; their sequence must be too.
    if (wire.orientation() == kernel::Orientation::Reversed)
      std::reverse(edges.begin(), edges.end());
    std::vector<kernel::Vec3> ring;
    for (const kernel::Shape& edge : edges) {
      std::vector<kernel::Vec3> points = edge_points(edge);
      if (edge.orientation() == kernel::Orientation::Reversed)
        std::reverse(points.begin(), points.end());
      // Without its logical end: the next edge of the wire starts there.
      if (!points.empty()) ring.insert(ring.end(), points.begin(), points.end() - 1);
    }
    ring.erase(std::unique(ring.begin(), ring.end()), ring.end());
    while (ring.size() > 1 && ring.front() == ring.back()) ring.pop_back();
    if (ring.size() < 3) {
      if (rings.empty()) return std::nullopt;  // no exterior: nothing to draw
      continue;
    }
    if (face.orientation() == kernel::Orientation::Reversed) std::reverse(ring.begin(), ring.end());
    rings.push_back(std::move(ring));
  }
  if (rings.empty()) return std::nullopt;
  return rings;
}

}  // namespace csgtile::worker::detail
