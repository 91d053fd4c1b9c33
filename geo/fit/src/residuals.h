#pragma once
// Residuals of points to a detected surface, shared by the RANSAC's detector
// (ransac_detector.h) and the merge of shapes on one surface (shape_merge.cpp).

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

#include "csgtile/fit/fit.h"

namespace csgtile::fit::detail {

/// RMS of the distances of `points[inliers]` to `s`; 0 for no inliers.
inline double surface_rms(const Surface& s, std::span<const kernel::Vec3> points,
                          std::span<const std::uint32_t> inliers) {
  double sum = 0.0;
  for (auto i : inliers) {
    const double d = surface_distance(s, points[i]);
    sum += d * d;
  }
  return std::sqrt(sum / static_cast<double>(std::max<std::size_t>(inliers.size(), 1)));
}

/// The median of `values` (the upper one of an even count); `values` must not be empty.
inline double median_of(std::vector<double> values) {
  const auto mid = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), mid, values.end());
  return *mid;
}

}  // namespace csgtile::fit::detail
