// Vegetation on unclassified tiles (fit_internal.h, VegetationOptions): a point is vegetation
// when most of its neighbours within a radius are of multi-return pulses or rough.

#include <array>
#include <cmath>
#include <map>

#include "fit_internal.h"

namespace csgtile::fit::detail {

std::vector<char> vegetation_mask(std::span<const Vec3> points, std::span<const double> curvature,
                                  std::span<const char> several, const VegetationOptions& options) {
  std::vector<char> out(points.size(), 0);
  if (curvature.size() != points.size() || several.size() != points.size() || points.empty()) {
    return out;
  }
  double r = options.radius;
  if (!(r > 0.0)) {
    std::vector<std::uint32_t> all(points.size());
    for (std::uint32_t i = 0; i < all.size(); ++i) all[i] = i;
    r = 4.0 * estimate_spacing(points, all);
  }
  if (!(r > 0.0) || !std::isfinite(r)) return out;
  auto key = [&](const Vec3& p) {
    return std::array<long long, 3>{static_cast<long long>(std::floor(p.x() / r)),
                                    static_cast<long long>(std::floor(p.y() / r)),
                                    static_cast<long long>(std::floor(p.z() / r))};
  };
  std::map<std::array<long long, 3>, std::vector<std::uint32_t>> grid;
  for (std::uint32_t i = 0; i < points.size(); ++i) {
    if (points[i].allFinite()) grid[key(points[i])].push_back(i);
  }
  const double r2 = r * r;
  for (std::uint32_t i = 0; i < points.size(); ++i) {
    if (!points[i].allFinite()) continue;
    const auto k = key(points[i]);
    long long near = 0, rough = 0;
    for (long long dz = -1; dz <= 1; ++dz) {
      for (long long dy = -1; dy <= 1; ++dy) {
        for (long long dx = -1; dx <= 1; ++dx) {
          const auto it = grid.find({k[0] + dx, k[1] + dy, k[2] + dz});
          if (it == grid.end()) continue;
          for (auto j : it->second) {
            if ((points[j] - points[i]).squaredNorm() > r2) continue;
            ++near;
            rough += (several[j] || curvature[j] > options.curvature) ? 1 : 0;
          }
        }
      }
    }
    out[i] = static_cast<double>(rough) > options.share * static_cast<double>(near) ? 1 : 0;
  }
  return out;
}

}  // namespace csgtile::fit::detail
