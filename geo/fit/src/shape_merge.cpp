// Shapes on one surface with a narrow gap between them become one (shape_merge.h).

#include "shape_merge.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "disjoint_sets.h"
#include "fit_internal.h"
#include "residuals.h"

namespace csgtile::fit::detail {

namespace {

using kernel::Vec3;

// The members of `set` in ascending x (ties: index), for the sweeps below.
std::vector<std::uint32_t> by_x(std::span<const Vec3> points, std::span<const std::uint32_t> set) {
  std::vector<std::uint32_t> order(set.begin(), set.end());
  std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
    if (points[a].x() != points[b].x()) return points[a].x() < points[b].x();
    return a < b;
  });
  return order;
}

// The 90 % quantile of the distances from each member of `order` (sorted by by_x) to its nearest
// other member (a sweep along x, stopping once the x-gap alone passes the best distance); 0 for
// fewer than 2.
double nearest_quantile(std::span<const Vec3> points, const std::vector<std::uint32_t>& order) {
  const std::size_t n = order.size();
  if (n < 2) return 0.0;
  std::vector<double> nearest(n, std::numeric_limits<double>::infinity());
  for (std::size_t k = 0; k < n; ++k) {
    const Vec3& p = points[order[k]];
    double best = nearest[k];
    for (std::size_t j = k + 1; j < n; ++j) {
      const Vec3& q = points[order[j]];
      if (q.x() - p.x() >= best) break;
      const double d = (q - p).norm();
      best = std::min(best, d);
      nearest[j] = std::min(nearest[j], d);
    }
    for (std::size_t j = k; j-- > 0;) {
      const Vec3& q = points[order[j]];
      if (p.x() - q.x() >= best) break;
      best = std::min(best, (q - p).norm());
    }
    nearest[k] = best;
  }
  const std::size_t at = (n - 1) * 9 / 10;
  std::nth_element(nearest.begin(), nearest.begin() + static_cast<std::ptrdiff_t>(at),
                   nearest.end());
  return nearest[at];
}

// Whether some point of `a` comes within `reach` of some point of `b` (a sweep along x over
// both sets sorted).
bool within_reach(std::span<const Vec3> points, const std::vector<std::uint32_t>& a,
                  const std::vector<std::uint32_t>& b, double reach) {
  std::size_t start = 0;
  for (const std::uint32_t i : a) {
    const Vec3& p = points[i];
    while (start < b.size() && points[b[start]].x() < p.x() - reach) ++start;
    for (std::size_t j = start; j < b.size() && points[b[j]].x() <= p.x() + reach; ++j) {
      if ((points[b[j]] - p).norm() <= reach) return true;
    }
  }
  return false;
}

// Whether 95 % of `inliers` lie within `epsilon` of `s`.
bool mostly_on(std::span<const Vec3> points, const Surface& s,
               std::span<const std::uint32_t> inliers, double epsilon) {
  std::size_t on = 0;
  for (const std::uint32_t i : inliers) {
    on += std::abs(surface_distance(s, points[i])) <= epsilon ? 1 : 0;
  }
  return on * 100 >= inliers.size() * 95;
}

// RMS of `shape`'s points to its surface refitted to them (the surface a shape was found with
// may lean towards points it has given away since).
double own_rms(std::span<const Vec3> points, const DetectedShape& shape) {
  const auto own = refine_surface(shape.surface, points, shape.inliers);
  return surface_rms(own ? *own : shape.surface, points, shape.inliers);
}

// Whether one surface refitted to the points of both `a` and `b` fits them within the larger
// of `exact` and ten times `own`, the larger RMS each fits its own points with.
bool fit_jointly(std::span<const Vec3> points, const DetectedShape& a, const DetectedShape& b,
                 double own, double exact) {
  std::vector<std::uint32_t> both(a.inliers.begin(), a.inliers.end());
  both.insert(both.end(), b.inliers.begin(), b.inliers.end());
  const auto joint = refine_surface(a.surface, points, both);
  if (!joint) return false;
  return surface_rms(*joint, points, both) <= std::max(exact, 10.0 * own);
}

}  // namespace

std::size_t merge_same_surface(std::span<const Vec3> points, std::vector<DetectedShape>& shapes,
                               std::vector<int>& assignment, double epsilon, double exact) {
  const std::size_t m = shapes.size();
  if (m < 2) return 0;
  // Each shape's own RMS (exact clouds), once: the shapes' points do not change until the
  // merges are made.
  std::vector<double> own(m, -1.0);
  auto own_of = [&](std::size_t s) {
    if (own[s] < 0.0) own[s] = own_rms(points, shapes[s]);
    return own[s];
  };
  std::vector<double> quantile(m);
  std::vector<std::vector<std::uint32_t>> sorted(m);
  for (std::size_t s = 0; s < m; ++s) {
    sorted[s] = by_x(points, shapes[s].inliers);
    quantile[s] = nearest_quantile(points, sorted[s]);
  }
  DisjointSets sets(m);
  std::size_t merges = 0;
  for (std::size_t a = 0; a < m; ++a) {
    for (std::size_t b = a + 1; b < m; ++b) {
      if (shapes[a].surface.type != shapes[b].surface.type || sets.root(a) == sets.root(b))
        continue;
      const double reach = kMergeGapFactor * std::max(quantile[a], quantile[b]);
      if (!(reach > 0.0) || !within_reach(points, sorted[a], sorted[b], reach)) continue;
      if (!mostly_on(points, shapes[a].surface, shapes[b].inliers, epsilon) ||
          !mostly_on(points, shapes[b].surface, shapes[a].inliers, epsilon)) {
        continue;
      }
      if (exact > 0.0 &&
          !fit_jointly(points, shapes[a], shapes[b], std::max(own_of(a), own_of(b)), exact)) {
        continue;
      }
      // The lower index stays the root: a merged shape keeps its first part's place.
      sets.join(a, b);
      ++merges;
    }
  }
  if (merges == 0) return 0;
  std::vector<DetectedShape> kept;
  std::vector<char> grown;  // per kept shape: whether another joined it
  std::vector<int> renumber(m, -1);
  for (std::size_t s = 0; s < m; ++s) {
    const std::size_t r = sets.root(s);
    if (r == s) {
      renumber[s] = static_cast<int>(kept.size());
      kept.push_back(std::move(shapes[s]));
      grown.push_back(0);
    } else {
      renumber[s] = renumber[r];  // r < s: already placed
      grown[static_cast<std::size_t>(renumber[r])] = 1;
      DetectedShape& into = kept[static_cast<std::size_t>(renumber[r])];
      into.inliers.insert(into.inliers.end(), shapes[s].inliers.begin(), shapes[s].inliers.end());
    }
  }
  for (std::size_t k = 0; k < kept.size(); ++k) {
    if (!grown[k]) continue;
    DetectedShape& shape = kept[k];
    std::sort(shape.inliers.begin(), shape.inliers.end());
    if (auto refit = refine_surface(shape.surface, points, shape.inliers)) {
      const bool keeps_all =
          std::all_of(shape.inliers.begin(), shape.inliers.end(), [&](std::uint32_t i) {
            return std::abs(surface_distance(*refit, points[i])) <= epsilon;
          });
      if (keeps_all) shape.surface = *refit;
    }
  }
  for (int& label : assignment) {
    if (label >= 0) label = renumber[static_cast<std::size_t>(label)];
  }
  shapes = std::move(kept);
  return merges;
}

}  // namespace csgtile::fit::detail
