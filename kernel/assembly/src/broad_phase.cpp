#include "broad_phase.h"

#include <algorithm>
#include <numeric>

namespace csgtile::assembly::detail {

std::vector<std::pair<int, int>> overlapping_boxes(const std::vector<kernel::BoundingBox>& boxes) {
  std::vector<int> order;
  order.reserve(boxes.size());
  for (std::size_t i = 0; i < boxes.size(); ++i) {
    if (!boxes[i].empty()) order.push_back(static_cast<int>(i));
  }
  std::sort(order.begin(), order.end(), [&](int a, int b) {
    const double xa = boxes[static_cast<std::size_t>(a)].min.x(),
                 xb = boxes[static_cast<std::size_t>(b)].min.x();
    return xa < xb || (xa == xb && a < b);
  });
  std::vector<std::pair<int, int>> pairs;
  for (std::size_t k = 0; k < order.size(); ++k) {
    const kernel::BoundingBox& a = boxes[static_cast<std::size_t>(order[k])];
    for (std::size_t m = k + 1; m < order.size(); ++m) {
      const kernel::BoundingBox& b = boxes[static_cast<std::size_t>(order[m])];
      if (b.min.x() > a.max.x()) break;
      if (a.intersects(b))
        pairs.emplace_back(std::min(order[k], order[m]), std::max(order[k], order[m]));
    }
  }
  std::sort(pairs.begin(), pairs.end());
  return pairs;
}

}  // namespace csgtile::assembly::detail
