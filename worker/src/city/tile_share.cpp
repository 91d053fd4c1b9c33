// Which buildings across a tile's edges its fit makes (see tile_share.h).

#include "city/tile_share.h"

#include <algorithm>

#include "csgtile/kernel/broad_phase.h"

namespace csgtile::worker::city {

namespace {

Extent grown(const Extent& e, double by) { return {e[0] - by, e[1] - by, e[2] + by, e[3] + by}; }

bool holds(const Extent& e, const kernel::Vec2& p) {
  return p.x() >= e[0] && p.x() <= e[2] && p.y() >= e[1] && p.y() <= e[3];
}

bool meets(const Extent& e, const kernel::Vec2& lo, const kernel::Vec2& hi) {
  return hi.x() >= e[0] && lo.x() <= e[2] && hi.y() >= e[1] && lo.y() <= e[3];
}

bool within(const Extent& e, const kernel::Vec2& lo, const kernel::Vec2& hi) {
  return lo.x() >= e[0] && hi.x() <= e[2] && lo.y() >= e[1] && hi.y() <= e[3];
}

// The first tile in run order whose extent holds `p`, null when none does.
const TileExtent* holder(const TileNeighbourhood& n, const kernel::Vec2& p) {
  const TileExtent* best = holds(n.self.extent, p) ? &n.self : nullptr;
  for (const TileExtent& t : n.neighbours) {
    if ((best == nullptr || t.tile < best->tile) && holds(t.extent, p)) best = &t;
  }
  return best;
}

// The owner of a building whose box is [lo, hi]: the first tile in run order whose extent
// holds the box's centre, else the first whose extent meets the box (a building over a gap
// between tiles); null when none does.
const TileExtent* owner(const TileNeighbourhood& n, const kernel::Vec2& lo,
                        const kernel::Vec2& hi) {
  if (const TileExtent* t = holder(n, 0.5 * (lo + hi))) return t;
  std::vector<const TileExtent*> tiles{&n.self};
  for (const TileExtent& t : n.neighbours) tiles.push_back(&t);
  std::sort(tiles.begin(), tiles.end(),
            [](const TileExtent* a, const TileExtent* b) { return a->tile < b->tile; });
  for (const TileExtent* t : tiles) {
    if (meets(t->extent, lo, hi)) return t;
  }
  return nullptr;
}

}  // namespace

Extent TileNeighbourhood::read_region() const { return grown(self.extent, halo); }

bool owns_point(const TileNeighbourhood& n, const kernel::Vec2& p) {
  return holder(n, p) == &n.self;
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
