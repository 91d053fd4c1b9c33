#pragma once
/// \file
/// Access algorithms (paper §3.2): the explorer, the child map (MapCsgChildShape) and the
/// ancestor index (MapCsgFatherShape).

#include <array>
#include <iterator>
#include <optional>
#include <unordered_map>
#include <vector>

#include "csgtile/kernel/shape.h"

namespace csgtile::kernel {

/// Walks the sub-shapes of one kind, depth first in child order, as seen through the root
/// (locations and orientations composed). A shared sub-shape is visited once per use (an
/// edge of a box twice, once per face). Sub-shapes below a shape of kind `avoid` are
/// skipped, and nothing below a found shape is visited. Use in a range-for:
///   for (const Shape& face : Explorer(solid, ShapeKind::Face)) …
/// O(size of the walked hierarchy); holds a reference-free copy of the root.
class Explorer {
 public:
  /// `avoid` = std::nullopt walks everything. The root itself is yielded when its kind
  /// matches.
  Explorer(const Shape& root, ShapeKind find, std::optional<ShapeKind> avoid = std::nullopt);

  class Iterator {
   public:
    using value_type = Shape;
    using difference_type = std::ptrdiff_t;
    using reference = const Shape&;
    using pointer = const Shape*;
    using iterator_category = std::input_iterator_tag;

    const Shape& operator*() const { return current_; }
    const Shape* operator->() const { return &current_; }
    Iterator& operator++();
    bool operator==(const Iterator& other) const { return done_ == other.done_ && done_; }
    bool operator!=(const Iterator& other) const { return !(*this == other); }

   private:
    friend class Explorer;
    struct Frame {
      Shape shape;
      std::size_t next_child = 0;
    };
    Iterator() = default;
    Iterator(const Shape& root, ShapeKind find, std::optional<ShapeKind> avoid);
    void advance();
    std::vector<Frame> stack_;
    Shape current_;
    ShapeKind find_ = ShapeKind::Vertex;
    std::optional<ShapeKind> avoid_;
    bool done_ = true;
  };

  Iterator begin() const { return Iterator(root_, find_, avoid_); }
  Iterator end() const { return Iterator(); }

 private:
  Shape root_;
  ShapeKind find_;
  std::optional<ShapeKind> avoid_;
};

/// Sub-shapes of one kind, each once (is_same: same body and location; orientation of the
/// first visit kept), in first-visit explorer order. Indices are 0-based and dense.
class ShapeIndex {
 public:
  /// Adds the shape if absent; returns its index either way.
  std::size_t add(const Shape& shape);
  /// Index of a shape, or npos.
  std::size_t find(const Shape& shape) const;
  bool contains(const Shape& shape) const { return find(shape) != npos; }
  std::size_t size() const { return shapes_.size(); }
  const Shape& operator[](std::size_t i) const { return shapes_[i]; }
  const std::vector<Shape>& shapes() const { return shapes_; }
  static constexpr std::size_t npos = static_cast<std::size_t>(-1);

 private:
  std::vector<Shape> shapes_;
  std::unordered_map<Shape, std::size_t, ShapeSameHash, ShapeSameEqual> index_;
};

/// MapCsgChildShape: every sub-shape of `kind` in `root`, once. O(n) expected.
ShapeIndex map_child_shapes(const Shape& root, ShapeKind kind);

/// MapCsgFatherShape: for each sub-shape of kind `child` in `root`, its ancestors of kind
/// `ancestor` (vertex→edges, edge→faces, face→shells or solids, …).
/// Keys are in first-visit order of the walk "ancestors in explorer order, then their
/// children in explorer order"; each key's ancestors are distinct (is_same), in the order
/// they were met, with the orientation of their first use. O(n) expected.
class AncestorIndex {
 public:
  AncestorIndex(const Shape& root, ShapeKind child, ShapeKind ancestor);
  const ShapeIndex& keys() const { return keys_; }
  std::size_t size() const { return keys_.size(); }
  /// Ancestors of the i-th key.
  const std::vector<Shape>& ancestors(std::size_t i) const { return ancestors_[i]; }
  /// Ancestors of a shape (empty if it is not a key).
  const std::vector<Shape>& ancestors_of(const Shape& child) const;

 private:
  ShapeIndex keys_;
  std::vector<std::vector<Shape>> ancestors_;
};

/// Number of distinct sub-shapes of each kind (is_same), indexed by ShapeKind.
std::array<std::size_t, kShapeKindCount> count_shapes(const Shape& root);

}  // namespace csgtile::kernel
