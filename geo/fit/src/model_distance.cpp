// How far a primitive's points lie from its solid (fit_internal.h): the fit quality a city
// model publishes per building, the RMSE of its points to the model.

#include <cmath>

#include "csgtile/kernel/mesh_distance.h"
#include "csgtile/kernel/tessellation.h"
#include "fit_internal.h"

namespace csgtile::fit::detail {

std::optional<BoundaryFit> boundary_fit(const kernel::Shape& solid, std::span<const Vec3> points,
                                        std::span<const std::uint32_t> members,
                                        double chordal_tolerance, double near) {
  if (members.empty()) return std::nullopt;
  kernel::TessellationOptions t;
  t.chordal_tolerance = chordal_tolerance;
  const auto mesh = kernel::tessellate(solid, t);
  if (!mesh.ok() || mesh.value().triangles.empty()) return std::nullopt;
  const kernel::MeshDistance model(mesh.value());
  double sum = 0.0;
  std::size_t counted = 0, within = 0;
  for (const std::uint32_t i : members) {
    const Vec3& p = points[i];
    if (!p.allFinite()) continue;
    const double best = model.distance2(p);
    sum += best;
    ++counted;
    if (best <= near * near) ++within;
  }
  if (counted == 0) return std::nullopt;
  const auto n = static_cast<double>(counted);
  return BoundaryFit{std::sqrt(sum / n), static_cast<double>(within) / n};
}

}  // namespace csgtile::fit::detail
