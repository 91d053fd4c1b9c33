// Which buildings across a tile's edges its fit makes (see tile_share.h).

#include "city/tile_share.h"

#include <algorithm>
#include <vector>

#include "csgtile/kernel/broad_phase.h"

namespace csgtile::worker::city {

namespace {

bool holds(const Extent& e, const kernel::Vec2& p) {
  return p.x() >= e[0] && p.x() <= e[2] && p.y() >= e[1] && p.y() <= e[3];
}

bool meets(const Extent& e, const kernel::Vec2& lo, const kernel::Vec2& hi) {
  return extents_meet(e, {lo.x(), lo.y(), hi.x(), hi.y()});
}

bool within(const Extent& e, const kernel::Vec2& lo, const kernel::Vec2& hi) {
  return lo.x() >= e[0] && hi.x() <= e[2] && lo.y() >= e[1] && hi.y() <= e[3];
}

// The first tile in run order (this one or a neighbour) whose extent passes `test`; null when
// none does.
template <typename Test>
const TileExtent* first(const TileNeighbourhood& n, Test test) {
  const TileExtent* best = test(n.self.extent) ? &n.self : nullptr;
  for (const TileExtent& t : n.neighbours) {
    if ((best == nullptr || t.tile < best->tile) && test(t.extent)) best = &t;
  }
  return best;
}

// The owner of a building whose box is [lo, hi]: the first tile in run order whose extent
// holds the box's centre, else the first whose extent meets the box (a building over a gap
// between tiles); null when none does.
const TileExtent* owner(const TileNeighbourhood& n, const kernel::Vec2& lo,
                        const kernel::Vec2& hi) {
  const kernel::Vec2 centre = 0.5 * (lo + hi);
  if (const TileExtent* t = first(n, [&](const Extent& e) { return holds(e, centre); })) return t;
  return first(n, [&](const Extent& e) { return meets(e, lo, hi); });
}

}  // namespace

Extent grown(const Extent& e, double by) { return {e[0] - by, e[1] - by, e[2] + by, e[3] + by}; }

bool extents_meet(const Extent& a, const Extent& b) {
  return a[2] >= b[0] && a[0] <= b[2] && a[3] >= b[1] && a[1] <= b[3];
}

Extent TileNeighbourhood::read_region() const { return grown(self.extent, halo); }

bool owns_point(const TileNeighbourhood& n, const kernel::Vec2& p) {
  return first(n, [&](const Extent& e) { return holds(e, p); }) == &n.self;
}

std::vector<std::vector<std::size_t>> neighbours_of(const std::vector<TileExtent>& all,
                                                    double distance) {
  std::vector<kernel::BoundingBox> boxes;
  boxes.reserve(all.size());
  for (const TileExtent& t : all) {
    // Grown by half the distance each: two boxes meet when their extents are within it.
    const Extent e = grown(t.extent, 0.5 * distance);
    kernel::BoundingBox b;
    b.add(kernel::Vec3(e[0], e[1], 0.0));
    b.add(kernel::Vec3(e[2], e[3], 0.0));
    boxes.push_back(b);
  }
  std::vector<std::vector<std::size_t>> out(all.size());
  for (const auto& [i, j] : kernel::overlapping_boxes(boxes)) {
    out[i].push_back(j);
    out[j].push_back(i);
  }
  for (auto& list : out) std::sort(list.begin(), list.end());
  return out;
}

fit::ShareKind footprint_share(const TileNeighbourhood& n, const kernel::Vec2& lo,
                               const kernel::Vec2& hi) {
  if (const TileExtent* o = owner(n, lo, hi);
      o != nullptr && within(grown(o->extent, n.halo), lo, hi)) {
    return *o == n.self ? fit::ShareKind::whole : fit::ShareKind::none;
  }
  return meets(n.self.extent, lo, hi) ? fit::ShareKind::own_points : fit::ShareKind::none;
}

fit::ShareKind cluster_share(const TileNeighbourhood& n, const kernel::Vec2& lo,
                             const kernel::Vec2& hi, double tolerance) {
  // Seen whole here? Points within the clustering distance of the read region's edge may
  // join points past it.
  if (!within(grown(n.read_region(), -tolerance), lo, hi)) return fit::ShareKind::own_points;
  if (const TileExtent* o = owner(n, lo, hi);
      o != nullptr && within(grown(o->extent, n.halo - tolerance), lo, hi)) {
    return *o == n.self ? fit::ShareKind::whole : fit::ShareKind::none;
  }
  return fit::ShareKind::own_points;
}

}  // namespace csgtile::worker::city
