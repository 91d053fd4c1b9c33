#pragma once
// The n-ary fuse's order: a balanced tree of pairwise fuses (neighbours in input order first),
// so that every argument takes part in about log2(n) operations instead of a growing
// accumulator taking part in n − 1. Where the fuse of two partial results fails, the right
// one is taken apart along its own tree and its halves are fused into the left one in turn,
// down to single arguments, and where that fails too, the left one is taken apart into the
// right one alike; an error there is returned (the first one; Cancelled at once). Used for shapes
// (boolean_fuse_all) and for shapes with their face history (csg_combine).

#include <utility>
#include <vector>

#include "csgtile/kernel/result.h"

namespace csgtile::kernel::detail {

/// `fuse(a, b)` returns Result<T>. Precondition: `items` is not empty.
template <class T, class Fuse>
Result<T> fuse_tree(const std::vector<T>& items, const Fuse& fuse) {
  struct Node {
    T value;
    int left, right;  // the nodes it was fused from; -1 for an argument
  };
  std::vector<Node> nodes;
  for (const T& item : items) nodes.push_back({item, -1, -1});
  // Fuses node `part` into `acc`, taking `part` apart where the whole does not fuse.
  auto fuse_into = [&](const auto& self, const T& acc, int part) -> Result<T> {
    const Node node = nodes[static_cast<std::size_t>(part)];
    auto fused = fuse(acc, node.value);
    // A cancelled fuse is not retried piece by piece: the interrupt stays fired.
    if (fused.ok() || node.left < 0 || fused.error().code == ErrorCode::Cancelled) return fused;
    auto first = self(self, acc, node.left);
    if (!first.ok()) return first;
    return self(self, first.value(), node.right);
  };
  std::vector<int> level;
  for (std::size_t i = 0; i < items.size(); ++i) level.push_back(static_cast<int>(i));
  while (level.size() > 1) {
    std::vector<int> next;
    for (std::size_t i = 0; i + 1 < level.size(); i += 2) {
      const auto left = static_cast<std::size_t>(level[i]);
      auto fused = fuse_into(fuse_into, nodes[left].value, level[i + 1]);
      if (!fused.ok() && fused.error().code != ErrorCode::Cancelled && nodes[left].left >= 0) {
        // The other way round: the left one taken apart into the right one. Fuses of fitted
        // solids can depend on the order (a cone fused with one of two end-to-end beams first
        // meets the other's coincident end face along its own new edge; both beams first, it
        // meets no end face).
        auto swapped =
            fuse_into(fuse_into, nodes[static_cast<std::size_t>(level[i + 1])].value, level[i]);
        if (swapped.ok()) fused = std::move(swapped);
      }
      if (!fused.ok()) return fused;
      nodes.push_back({std::move(fused).value(), level[i], level[i + 1]});
      next.push_back(static_cast<int>(nodes.size()) - 1);
    }
    if (level.size() % 2 == 1) next.push_back(level.back());
    level = std::move(next);
  }
  return nodes[static_cast<std::size_t>(level.front())].value;
}

}  // namespace csgtile::kernel::detail
