// The broad phase (csgtile/kernel/broad_phase.h).

#include "csgtile/kernel/broad_phase.h"

#include <algorithm>

namespace csgtile::kernel {

BoxSweep::BoxSweep(std::span<const BoundingBox> boxes) : boxes_(boxes) {
  order_.reserve(boxes.size());
  for (std::size_t i = 0; i < boxes.size(); ++i) {
    if (!boxes[i].empty()) order_.push_back(i);
  }
  std::sort(order_.begin(), order_.end(), [&](std::size_t a, std::size_t b) {
    const double xa = boxes[a].min.x(), xb = boxes[b].min.x();
    return xa < xb || (xa == xb && a < b);
  });
}

void BoxSweep::pairs(std::size_t first, std::size_t last, std::vector<BoxPair>& out) const {
  last = std::min(last, order_.size());
  for (std::size_t k = first; k < last; ++k) {
    const BoundingBox& a = boxes_[order_[k]];
    for (std::size_t m = k + 1; m < order_.size(); ++m) {
      const BoundingBox& b = boxes_[order_[m]];
      if (b.min.x() > a.max.x()) break;
      if (a.intersects(b))
        out.emplace_back(std::min(order_[k], order_[m]), std::max(order_[k], order_[m]));
    }
  }
}

std::vector<BoxPair> overlapping_boxes(std::span<const BoundingBox> boxes) {
  const BoxSweep sweep(boxes);
  std::vector<BoxPair> out;
  sweep.pairs(0, sweep.size(), out);
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace csgtile::kernel
