// Houses whose solids overlap become one (see house_overlaps.h).

#include "house_overlaps.h"

#include <algorithm>
#include <map>
#include <string>

#include "csgtile/kernel/broad_phase.h"
#include "disjoint_sets.h"
#include "synth/ray_internal.h"

namespace csgtile::fit::detail {

namespace {

// Whether the two solids hold a common point: a 10 × 10 × 10 lattice over the common part of
// their boxes, shrunk by `margin`, sampled at its cells' centres.
bool overlap(const geo::detail::PreparedPrimitive& a, const geo::detail::PreparedPrimitive& b,
             double margin) {
  const kernel::Vec3 lo = a.world_bounds.min.cwiseMax(b.world_bounds.min).array() + margin;
  const kernel::Vec3 hi = a.world_bounds.max.cwiseMin(b.world_bounds.max).array() - margin;
  if (!(hi.array() > lo.array()).all()) return false;
  constexpr int kSteps = 10;
  for (int i = 0; i < kSteps; ++i) {
    for (int j = 0; j < kSteps; ++j) {
      for (int k = 0; k < kSteps; ++k) {
        const kernel::Vec3 t((i + 0.5) / kSteps, (j + 0.5) / kSteps, (k + 0.5) / kSteps);
        const kernel::Vec3 q = lo + t.cwiseProduct(hi - lo);
        if (geo::detail::primitive_contains(a, q) && geo::detail::primitive_contains(b, q)) {
          return true;
        }
      }
    }
  }
  return false;
}

}  // namespace

void join_overlapping_houses(std::vector<geo::ScenePrimitive>& primitives,
                             const std::vector<int>& region, double margin) {
  // Each derived primitive's key: its house, else its region as a whole.
  std::map<std::string, int> key_of;
  std::vector<int> key(primitives.size(), -1);
  std::vector<std::string> house_of_key;
  bool any_house = false;
  for (std::size_t k = 0; k < primitives.size() && k < region.size(); ++k) {
    const geo::ScenePrimitive& p = primitives[k];
    if (!p.building.empty()) continue;
    any_house = any_house || !p.house.empty();
    const std::string name = p.house.empty() ? "\n" + std::to_string(region[k]) : p.house;
    const auto [it, added] = key_of.emplace(name, static_cast<int>(house_of_key.size()));
    if (added) house_of_key.push_back(p.house);
    key[k] = it->second;
  }
  if (!any_house) return;
  std::vector<geo::detail::PreparedPrimitive> prepared(primitives.size());
  std::vector<kernel::BoundingBox> boxes(primitives.size());
  for (std::size_t k = 0; k < primitives.size(); ++k) {
    if (key[k] < 0) continue;
    prepared[k] = geo::detail::prepare_primitive(primitives[k].spec);
    boxes[k] = prepared[k].world_bounds;
  }
  DisjointSets sets(house_of_key.size());
  auto root = [&sets](int x) { return sets.root(static_cast<std::size_t>(x)); };
  // Per set (by its root): whether a house is in it.
  std::vector<char> housed(house_of_key.size(), 0);
  for (std::size_t x = 0; x < house_of_key.size(); ++x) housed[x] = house_of_key[x].empty() ? 0 : 1;
  for (const auto& [i, j] : kernel::overlapping_boxes(boxes)) {
    if (key[i] < 0 || key[j] < 0) continue;
    const std::size_t a = root(key[i]), b = root(key[j]);
    // One house; or two regions without houses, which fuse as they touch anyway.
    if (a == b || (!housed[a] && !housed[b])) continue;
    if (!overlap(prepared[i], prepared[j], margin)) continue;
    sets.join(a, b);
    housed[std::min(a, b)] = 1;
  }
  // Each joined set takes the name of its first house (keys are in the order of their first
  // primitive).
  std::vector<std::string> name(house_of_key.size());
  for (std::size_t x = 0; x < house_of_key.size(); ++x) {
    std::string& n = name[sets.root(x)];
    if (n.empty()) n = house_of_key[x];
  }
  for (std::size_t k = 0; k < primitives.size(); ++k) {
    if (key[k] >= 0) primitives[k].house = name[root(key[k])];
  }
}

}  // namespace csgtile::fit::detail
