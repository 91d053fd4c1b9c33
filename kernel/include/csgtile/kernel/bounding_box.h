#pragma once
/// \file
/// Axis-aligned bounding box.

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

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

/// A ray origin + t·direction for slab tests against boxes: the one ray–box test of the
/// solid classifier's rays, its box tree, the scan simulator's hierarchy and the Boolean's
/// section lines (whose clipped parameters become curve bounds).
struct BoxRay {
  Vec3 origin;
  Vec3 direction;

  BoxRay(const Vec3& o, const Vec3& d) : origin(o), direction(d) {}

  /// Narrows [t0, t1] to the parameters of the ray inside `box` (closed: touching counts);
  /// false when none is left. On a flat axis (direction exactly 0) the origin must lie within
  /// the box's slab. The slab ends are divided by the direction, not multiplied by its
  /// reciprocal, so a parameter is the correctly rounded quotient.
  bool clip(const BoundingBox& box, double& t0, double& t1) const {
    if (box.empty()) return false;
    for (int i = 0; i < 3; ++i) {
      if (direction[i] == 0.0) {
        if (origin[i] < box.min[i] || origin[i] > box.max[i]) return false;
        continue;
      }
      double a = (box.min[i] - origin[i]) / direction[i];
      double b = (box.max[i] - origin[i]) / direction[i];
      if (a > b) std::swap(a, b);
      t0 = std::max(t0, a);
      t1 = std::min(t1, b);
      if (t0 > t1) return false;
    }
    return true;
  }
};

}  // namespace csgtile::kernel
