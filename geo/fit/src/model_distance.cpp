// How far a primitive's points lie from its solid (fit_internal.h): the fit quality a city
// model publishes per building, the RMSE of its points to the model.

#include <algorithm>
#include <cmath>
#include <limits>

#include "csgtile/kernel/tessellation.h"
#include "fit_internal.h"

namespace csgtile::fit::detail {

namespace {

using kernel::Vec3;

// Squared distance from p to the triangle (a, b, c): the closest point found by the regions
// of the triangle's plane (vertex, edge or face region), as in Ericson's Real-Time Collision
// Detection, §5.1.5.
double triangle_distance2(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0.0 && d2 <= 0.0) return ap.squaredNorm();
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0.0 && d4 <= d3) return bp.squaredNorm();
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) return (ap - d1 / (d1 - d3) * ab).squaredNorm();
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0.0 && d5 <= d6) return cp.squaredNorm();
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) return (ap - d2 / (d2 - d6) * ac).squaredNorm();
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0) {
    return (bp - (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b)).squaredNorm();
  }
  const double scale = 1.0 / (va + vb + vc);
  return (ap - vb * scale * ab - vc * scale * ac).squaredNorm();
}

}  // namespace

std::optional<BoundaryFit> boundary_fit(const kernel::Shape& solid, std::span<const Vec3> points,
                                        std::span<const std::uint32_t> members,
                                        double chordal_tolerance, double near) {
  if (members.empty()) return std::nullopt;
  kernel::TessellationOptions t;
  t.chordal_tolerance = chordal_tolerance;
  const auto mesh = kernel::tessellate(solid, t);
  if (!mesh.ok() || mesh.value().triangles.empty()) return std::nullopt;
  const kernel::Mesh& m = mesh.value();
  struct Triangle {
    Vec3 a, b, c, low, high;
  };
  std::vector<Triangle> triangles;
  triangles.reserve(m.triangles.size());
  for (const auto& k : m.triangles) {
    Triangle tri{m.vertices[k[0]], m.vertices[k[1]], m.vertices[k[2]], {}, {}};
    tri.low = tri.a.cwiseMin(tri.b).cwiseMin(tri.c);
    tri.high = tri.a.cwiseMax(tri.b).cwiseMax(tri.c);
    triangles.push_back(tri);
  }
  double sum = 0.0;
  std::size_t counted = 0, within = 0;
  for (const std::uint32_t i : members) {
    const Vec3& p = points[i];
    if (!p.allFinite()) continue;
    double best = std::numeric_limits<double>::infinity();
    for (const Triangle& tri : triangles) {
      // A triangle whose box is farther than the best so far cannot be closer.
      const Vec3 gap = (tri.low - p).cwiseMax(p - tri.high).cwiseMax(Vec3::Zero());
      if (gap.squaredNorm() >= best) continue;
      best = std::min(best, triangle_distance2(p, tri.a, tri.b, tri.c));
    }
    sum += best;
    ++counted;
    if (best <= near * near) ++within;
  }
  if (counted == 0) return std::nullopt;
  const auto n = static_cast<double>(counted);
  return BoundaryFit{std::sqrt(sum / n), static_cast<double>(within) / n};
}

}  // namespace csgtile::fit::detail
