// One ground under a building: vertical extrusions whose footprints touch and whose bases lie
// within the ground filter's own height tolerance of each other stand on the lowest of those
// bases. Each part's base comes from the ground cells under its own footprint, so the parts
// of one building stand millimetres to centimetres apart; fused, such steps become sliver
// faces and notched walls (non-planar polygons for val3dity) that no building has.

#include <algorithm>
#include <cmath>
#include <numeric>
#include <vector>

#include "fit_internal.h"

namespace csgtile::fit::detail {

namespace {

using kernel::Vec3;

struct Base {
  std::size_t index = 0;  // into the primitives
  double z = 0.0;
  double min_x = 0, min_y = 0, max_x = 0, max_y = 0;
};

std::size_t find(std::vector<std::size_t>& parent, std::size_t i) {
  while (parent[i] != i) i = parent[i] = parent[parent[i]];
  return i;
}

}  // namespace

std::size_t snap_extrusion_bases(std::vector<geo::ScenePrimitive>& primitives, double tolerance) {
  if (!(tolerance > 0.0)) return 0;
  std::vector<Base> bases;
  for (std::size_t i = 0; i < primitives.size(); ++i) {
    const kernel::PrimitiveSpec& s = primitives[i].spec;
    if (s.type != kernel::PrimitiveType::Extrusion || s.profile.empty()) continue;
    const Eigen::Matrix3d& r = s.placement.rotation();
    if (std::abs(r(2, 2) - 1.0) > 1e-12) continue;  // only extrusions along the vertical
    Base b;
    b.index = i;
    b.z = s.placement.translation().z();
    b.min_x = b.min_y = INFINITY;
    b.max_x = b.max_y = -INFINITY;
    for (const auto& q : s.profile) {
      const Vec3 w = s.placement.apply_point(Vec3(q.x(), q.y(), 0.0));
      b.min_x = std::min(b.min_x, w.x());
      b.max_x = std::max(b.max_x, w.x());
      b.min_y = std::min(b.min_y, w.y());
      b.max_y = std::max(b.max_y, w.y());
    }
    bases.push_back(b);
  }
  // Buildings: footprints whose boxes touch (a centimetre of slack), transitively.
  constexpr double kTouch = 0.01;
  std::vector<std::size_t> parent(bases.size());
  std::iota(parent.begin(), parent.end(), std::size_t{0});
  std::vector<std::size_t> order(bases.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::sort(order.begin(), order.end(),
            [&](std::size_t a, std::size_t b) { return bases[a].min_x < bases[b].min_x; });
  for (std::size_t i = 0; i < order.size(); ++i) {
    const Base& a = bases[order[i]];
    for (std::size_t j = i + 1; j < order.size(); ++j) {
      const Base& b = bases[order[j]];
      if (b.min_x > a.max_x + kTouch) break;
      if (b.min_y > a.max_y + kTouch || a.min_y > b.max_y + kTouch) continue;
      parent[find(parent, order[i])] = find(parent, order[j]);
    }
  }
  std::vector<std::vector<std::size_t>> groups(bases.size());
  for (std::size_t i = 0; i < bases.size(); ++i) groups[find(parent, i)].push_back(i);
  std::size_t moved = 0;
  for (auto& group : groups) {
    if (group.size() < 2) continue;
    std::sort(group.begin(), group.end(), [&](std::size_t a, std::size_t b) {
      return bases[a].z < bases[b].z ||
             (bases[a].z == bases[b].z && bases[a].index < bases[b].index);
    });
    double level = bases[group.front()].z;
    for (std::size_t k : group) {
      const Base& b = bases[k];
      if (b.z - level > tolerance) level = b.z;  // a step of its own: a new level
      const double drop = b.z - level;
      if (drop <= 0.0) continue;
      kernel::PrimitiveSpec& s = primitives[b.index].spec;
      Vec3 t = s.placement.translation();
      t.z() = level;
      auto moved_placement =
          kernel::Location::from_parts(s.placement.rotation(), s.placement.scale(), t);
      if (!moved_placement.ok()) continue;
      s.placement = moved_placement.value();
      s.height += drop;  // the top stays where it was
      // Clips are half-spaces n·p ≤ d in the local frame, which moved down by `drop`.
      for (auto& c : s.clips) c.w() += c.z() * drop;
      ++moved;
    }
  }
  return moved;
}

}  // namespace csgtile::fit::detail
