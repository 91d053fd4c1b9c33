#pragma once
/// \file
/// How far points lie from a triangle mesh (a model's boundary through tessellate()), and
/// whether a point stands over it: the queries a fit quality needs ("RMSE of the building's
/// points to its LoD2.2 model", as 3DBAG publishes it).

#include <array>
#include <cstdint>
#include <vector>

#include "csgtile/kernel/bounding_box.h"
#include "csgtile/kernel/tessellation.h"

namespace csgtile::kernel {

/// A mesh's triangles bucketed on a grid in the xy plane. Built once, then queried from any
/// number of threads (every query is const and allocation-free).
class MeshDistance {
 public:
  explicit MeshDistance(const Mesh& mesh);

  /// Euclidean distance from `p` to the nearest point of any triangle (exact, not the
  /// nearest vertex); +infinity for a mesh without triangles.
  double distance(const Vec3& p) const;
  double distance2(const Vec3& p) const;  ///< its square (exactly what distance() roots)
  /// Whether the vertical line through (x, y) meets a triangle that is not vertical (points
  /// on a triangle's edge count): the point stands over or under the mesh.
  bool covers(double x, double y) const;
  /// The box of the triangles (empty for a mesh without triangles).
  const BoundingBox& bounds() const { return bounds_; }

 private:
  struct Triangle {
    Vec3 a, b, c, low, high;
  };
  std::vector<Triangle> triangles_;
  BoundingBox bounds_;
  double x0_ = 0.0, y0_ = 0.0, cell_ = 1.0;
  long long nx_ = 0, ny_ = 0;
  std::vector<std::uint32_t> start_;  ///< per cell (row-major, x fastest), then one past the end
  std::vector<std::uint32_t> items_;  ///< triangle indices, cell after cell
};

/// Squared distance from `p` to the triangle (a, b, c) (degenerate triangles included).
double triangle_distance2(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c);

}  // namespace csgtile::kernel
