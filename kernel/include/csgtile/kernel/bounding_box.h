#pragma once
/// \file
/// Axis-aligned bounding box.

#include <limits>

#include "csgtile/kernel/location.h"

namespace csgtile::kernel {

/// An axis-aligned box; empty until a point is added.
struct BoundingBox {
  Vec3 min = Vec3::Constant(std::numeric_limits<double>::infinity());
  Vec3 max = Vec3::Constant(-std::numeric_limits<double>::infinity());

  bool empty() const { return min.x() > max.x(); }
  void add(const Vec3& p) {
    min = min.cwiseMin(p);
    max = max.cwiseMax(p);
  }
  void add(const BoundingBox& b) {
    if (!b.empty()) {
      min = min.cwiseMin(b.min);
      max = max.cwiseMax(b.max);
    }
  }
  /// Grows the box by `d` on every side.
  void enlarge(double d) {
    if (!empty()) {
      min.array() -= d;
      max.array() += d;
    }
  }
  bool intersects(const BoundingBox& b) const {
    return !empty() && !b.empty() && (min.array() <= b.max.array()).all() &&
           (b.min.array() <= max.array()).all();
  }
  bool contains(const Vec3& p) const {
    return (min.array() <= p.array()).all() && (p.array() <= max.array()).all();
  }
  Vec3 size() const { return empty() ? Vec3::Zero() : Vec3(max - min); }
};

}  // namespace csgtile::kernel
