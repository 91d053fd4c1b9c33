// The broad phase on TBB (csgtile/assembly/broad_phase.h).

#include "csgtile/assembly/broad_phase.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <cstddef>

namespace csgtile::assembly {

namespace {
// Sweep positions per task: enough work to outweigh a task, few enough blocks to balance.
constexpr std::size_t kBlock = 512;
}  // namespace

std::vector<kernel::BoxPair> parallel_overlapping_boxes(
    std::span<const kernel::BoundingBox> boxes) {
  const kernel::BoxSweep sweep(boxes);
  const std::size_t blocks = (sweep.size() + kBlock - 1) / kBlock;
  std::vector<std::vector<kernel::BoxPair>> found(blocks);
  tbb::parallel_for(std::size_t{0}, blocks,
                    [&](std::size_t b) { sweep.pairs(b * kBlock, (b + 1) * kBlock, found[b]); });
  std::size_t total = 0;
  for (const auto& f : found) total += f.size();
  std::vector<kernel::BoxPair> out;
  out.reserve(total);
  for (const auto& f : found) out.insert(out.end(), f.begin(), f.end());
  tbb::parallel_sort(out.begin(), out.end());
  return out;
}

}  // namespace csgtile::assembly
