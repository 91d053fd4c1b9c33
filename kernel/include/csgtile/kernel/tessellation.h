#pragma once
/// \file
/// Tessellation: watertight triangle meshes within a chordal tolerance. Every edge is
/// discretised once and its points are shared by the faces that use it, so the mesh of a
/// closed solid is closed and oriented, and its volume converges to the exact one as the
/// tolerance shrinks (an inscribed mesh: it is slightly smaller than the solid).

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "csgtile/kernel/shape.h"

namespace csgtile::kernel {

struct TessellationOptions {
  /// Maximum distance between the mesh and the exact geometry, metres (world units of the
  /// tessellated shape). Must be finite and > 0.
  double chordal_tolerance = 0.01;
  /// Maximum angle (radians) between consecutive segment directions on curves. Must be in
  /// (0, π]; values above 2π/3 act as 2π/3 so that a closed curve has at least 3 segments.
  double angular_tolerance = 0.5;
  /// Triangulate every face with the general method (boundary polygon in the (u, v) plane,
  /// then interior refinement) instead of the row method for rectangular domains. The
  /// general method is what faces with non-rectangular domains always get; this switch is
  /// for validating it on the primitives. Slower and less regular.
  bool general_method_only = false;
};

/// An indexed triangle mesh.
struct Mesh {
  /// Topological vertices first (map_child_shapes(shape, Vertex) order), then the interior
  /// points of edges (map_child_shapes(shape, Edge) order), then face interior points.
  std::vector<Vec3> vertices;
  /// Counter-clockwise seen from outside (the side a face's orientation marks as outward).
  std::vector<std::array<std::uint32_t, 3>> triangles;
  /// Index of the source face (map_child_shapes(shape, Face) order) of each triangle.
  std::vector<std::uint32_t> triangle_face;
  /// Per edge (map_child_shapes(shape, Edge) order): its mesh vertices from the start to the
  /// end of its curve's parameter range (a closed edge starts and ends on the same vertex;
  /// a degenerate edge is its single vertex).
  std::vector<std::vector<std::uint32_t>> edge_vertices;
};

/// Tessellates every face of `shape` (any kind) once, as map_child_shapes(shape, Face)
/// lists it: placed by its composed Location and oriented by its first use (a face shared
/// by two solids of a compsolid is meshed once; faces used Internal or External bound
/// nothing and are skipped). Triangles of a face used Reversed are flipped. Each edge is
/// sampled once and its points are shared by its faces, so closed shells give closed meshes.
/// Zero-area triangles are never emitted. Curved faces with a rectangular (u, v) domain (the
/// primitives') are meshed in rows; other faces by the general method (see
/// general_method_only). Errors: InvalidArgument (null shape, tolerance out of range or too
/// small for the model), DegenerateGeometry (a face boundary that cannot be triangulated).
/// Deterministic. Linear in the output for rows; planar faces are quadratic in their boundary
/// points; the general method costs a few hash lookups per flip. Thread-safe.
Result<Mesh> tessellate(const Shape& shape, const TessellationOptions& options = {});

/// `given` when a caller already has the shape's tessellation at `chordal_tolerance` (one mesh
/// shared by several users, e.g. a cell's exporters), else tessellate(shape) at that tolerance
/// made now. Errors: as tessellate.
Result<std::shared_ptr<const Mesh>> shared_tessellation(const Shape& shape,
                                                        double chordal_tolerance,
                                                        std::shared_ptr<const Mesh> given = {});

/// Parameters t_0 = first < … < t_k = last at which an edge's curve is sampled for the given
/// tolerances (world units: the body frame's tolerance is divided by the edge's scale):
/// lines give their ends, circles a uniform subdivision, polylines all their breakpoints in
/// range, other curves a uniform subdivision bounded by their curvature; a degenerate edge
/// gives {first, last}. Empty when more than 2^20 segments would be needed.
/// tessellate() passes half the chordal tolerance for edges of doubly curved faces (sphere,
/// torus, curved revolutions, whose interior error adds the errors along u and v) and of
/// faces meshed by the general method, and refines circles bounding a cone to the step its
/// widest circle needs.
std::vector<double> discretize_edge(const Shape& edge, double chordal_tolerance,
                                    double angular_tolerance);

/// Signed volume enclosed by the triangles (positive for a closed outward mesh); computed
/// about the bounding-box centre to limit cancellation at large coordinates.
double mesh_volume(const Mesh& mesh);
/// Total triangle area.
double mesh_area(const Mesh& mesh);
/// Every undirected edge used by exactly two triangles, in opposite directions (and no
/// triangle repeats a vertex). True for an empty mesh. O(n log n).
bool mesh_is_closed(const Mesh& mesh);

/// Binary STL bytes: 80-byte header, little-endian triangle count, 50 bytes per triangle
/// (normal, three vertices as float32, zero attribute). Used by size benchmarks.
std::string to_binary_stl(const Mesh& mesh);

}  // namespace csgtile::kernel
