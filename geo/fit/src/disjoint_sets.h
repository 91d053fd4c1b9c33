#pragma once
// Disjoint sets (union–find) over 0..n-1 whose root is always the set's smallest member, so
// that a joined set keeps its first member's place: the houses of a block (houses.cpp), houses
// that overlap (house_overlaps.cpp, primitives.cpp), shapes on one surface (shape_merge.cpp).

#include <algorithm>
#include <cstddef>
#include <numeric>
#include <vector>

namespace csgtile::fit::detail {

class DisjointSets {
 public:
  explicit DisjointSets(std::size_t n) : parent_(n) {
    std::iota(parent_.begin(), parent_.end(), std::size_t{0});
  }
  std::size_t root(std::size_t x) {
    while (parent_[x] != x) x = parent_[x] = parent_[parent_[x]];
    return x;
  }
  /// Joins the sets of a and b under the smaller root; false when they were one already.
  bool join(std::size_t a, std::size_t b) {
    const std::size_t ra = root(a), rb = root(b);
    if (ra == rb) return false;
    parent_[std::max(ra, rb)] = std::min(ra, rb);
    return true;
  }

 private:
  std::vector<std::size_t> parent_;
};

}  // namespace csgtile::fit::detail
