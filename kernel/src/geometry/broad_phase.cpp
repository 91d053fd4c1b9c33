// The broad phase (csgtile/kernel/broad_phase.h).

#include "csgtile/kernel/broad_phase.h"

#include <algorithm>

namespace csgtile::kernel {

std::vector<std::pair<std::size_t, std::size_t>> overlapping_boxes(
    std::span<const BoundingBox> boxes) {
  std::vector<std::size_t> order;
  order.reserve(boxes.size());
  for (std::size_t i = 0; i < boxes.size(); ++i) {
    if (!boxes[i].empty()) order.push_back(i);
  }
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    const double xa = boxes[a].min.x(), xb = boxes[b].min.x();
    return xa < xb || (xa == xb && a < b);
  });
  std::vector<std::pair<std::size_t, std::size_t>> pairs;
  for (std::size_t k = 0; k < order.size(); ++k) {
    const BoundingBox& a = boxes[order[k]];
    for (std::size_t m = k + 1; m < order.size(); ++m) {
      const BoundingBox& b = boxes[order[m]];
      if (b.min.x() > a.max.x()) break;
      if (a.intersects(b))
        pairs.emplace_back(std::min(order[k], order[m]), std::max(order[k], order[m]));
    }
  }
  std::sort(pairs.begin(), pairs.end());
  return pairs;
}

}  // namespace csgtile::kernel
