#pragma once
/// \file
/// The broad phase: which boxes of a set meet. One sweep for every caller: the n-ary fuse's
/// groups run it here, the assembly's candidate pairs and the topology index's relations run
/// it on TBB (csgtile/assembly/broad_phase.h cuts the same sweep into blocks).

#include <cstddef>
#include <span>
#include <utility>
#include <vector>

#include "csgtile/kernel/bounding_box.h"

namespace csgtile::kernel {

using BoxPair = std::pair<std::size_t, std::size_t>;

/// The sweep along x: the non-empty boxes ordered by their minimum x (ties by index). Each
/// sweep position meets the later positions whose minimum x does not pass its maximum x.
/// Boxes are used as given (enlarge them by the tolerance first) and must outlive the sweep.
class BoxSweep {
 public:
  explicit BoxSweep(std::span<const BoundingBox> boxes);

  /// Number of sweep positions (the non-empty boxes).
  std::size_t size() const { return order_.size(); }

  /// Appends, unsorted, the pairs (i < j, box indices) of the boxes at sweep positions
  /// [first, last) with every later box they meet (closed boxes: touching counts). Blocks of
  /// positions are independent: together they give each intersecting pair once.
  void pairs(std::size_t first, std::size_t last, std::vector<BoxPair>& out) const;

 private:
  std::span<const BoundingBox> boxes_;
  std::vector<std::size_t> order_;
};

/// Index pairs (i < j) of the boxes that intersect (an empty box meets nothing), sorted: the
/// whole sweep on the calling thread. O(n log n + the pairs whose x-intervals overlap).
std::vector<BoxPair> overlapping_boxes(std::span<const BoundingBox> boxes);

}  // namespace csgtile::kernel
