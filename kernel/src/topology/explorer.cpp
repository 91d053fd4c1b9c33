#include "csgtile/kernel/explorer.h"

#include <unordered_set>

namespace csgtile::kernel {

namespace {
// A shape can hold a shape of kind `find` only if it is of a more complex kind, or is a
// compound (which may hold anything, even other compounds).
bool may_contain(ShapeKind container, ShapeKind find) {
  return container == ShapeKind::Compound || static_cast<int>(container) < static_cast<int>(find);
}
}  // namespace

Explorer::Explorer(const Shape& root, ShapeKind find, std::optional<ShapeKind> avoid)
    : root_(root), find_(find), avoid_(avoid) {}

Explorer::Iterator::Iterator(const Shape& root, ShapeKind find, std::optional<ShapeKind> avoid)
    : find_(find), avoid_(avoid) {
  if (root.is_null()) return;
  if (root.kind() == find) {
    current_ = root;
    done_ = false;
    return;
  }
  if (avoid_ && root.kind() == *avoid_) return;
  if (!may_contain(root.kind(), find)) return;
  stack_.push_back({root, 0});
  done_ = false;
  advance();
}

Explorer::Iterator& Explorer::Iterator::operator++() {
  advance();
  return *this;
}

void Explorer::Iterator::advance() {
  while (!stack_.empty()) {
    Frame& top = stack_.back();
    if (top.next_child >= top.shape.child_count()) {
      stack_.pop_back();
      continue;
    }
    Shape child = top.shape.child(top.next_child++);
    const ShapeKind k = child.kind();
    if (k == find_) {
      current_ = std::move(child);
      return;
    }
    if (avoid_ && k == *avoid_) continue;
    if (may_contain(k, find_)) stack_.push_back({std::move(child), 0});
  }
  current_ = Shape();
  done_ = true;
}

std::size_t ShapeIndex::add(const Shape& shape) {
  auto [it, inserted] = index_.emplace(shape, shapes_.size());
  if (inserted) shapes_.push_back(shape);
  return it->second;
}

std::size_t ShapeIndex::find(const Shape& shape) const {
  auto it = index_.find(shape);
  return it == index_.end() ? npos : it->second;
}

ShapeIndex map_child_shapes(const Shape& root, ShapeKind kind) {
  ShapeIndex index;
  for (const Shape& s : Explorer(root, kind)) index.add(s);
  return index;
}

AncestorIndex::AncestorIndex(const Shape& root, ShapeKind child, ShapeKind ancestor) {
  // Each distinct ancestor is walked once: a face reached twice (compound holding the same
  // solid twice at the same location) adds nothing new.
  ShapeIndex seen_ancestors;
  for (const Shape& a : Explorer(root, ancestor)) {
    const std::size_t before = seen_ancestors.size();
    if (seen_ancestors.add(a) != before) continue;
    for (const Shape& c : Explorer(a, child)) {
      const std::size_t k = keys_.add(c);
      if (k == ancestors_.size()) ancestors_.emplace_back();
      std::vector<Shape>& list = ancestors_[k];
      // An ancestor is appended once per key; it can only repeat as the latest entry
      // because each ancestor's children are walked together (a seam edge used twice).
      if (list.empty() || !list.back().is_same(a)) list.push_back(a);
    }
  }
}

const std::vector<Shape>& AncestorIndex::ancestors_of(const Shape& child) const {
  static const std::vector<Shape> kEmpty;
  const std::size_t i = keys_.find(child);
  return i == ShapeIndex::npos ? kEmpty : ancestors_[i];
}

std::array<std::size_t, kShapeKindCount> count_shapes(const Shape& root) {
  std::array<std::size_t, kShapeKindCount> counts{};
  if (root.is_null()) return counts;
  // One walk over the whole hierarchy, deduplicated per (body, location); a shared
  // sub-shape's own children are not walked again.
  std::unordered_set<Shape, ShapeSameHash, ShapeSameEqual> seen;
  std::vector<Shape> stack{root};
  while (!stack.empty()) {
    Shape s = std::move(stack.back());
    stack.pop_back();
    if (!seen.insert(s).second) continue;
    ++counts[static_cast<int>(s.kind())];
    for (std::size_t i = 0; i < s.child_count(); ++i) stack.push_back(s.child(i));
  }
  return counts;
}

}  // namespace csgtile::kernel
