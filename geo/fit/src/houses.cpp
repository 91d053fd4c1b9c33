// Houses of a block from its roof partition (see houses.h).

#include "houses.h"

#include "disjoint_sets.h"

#include <map>
#include <utility>

namespace csgtile::fit::detail {

std::vector<int> group_houses(const std::vector<HousePart>& parts,
                              const std::vector<PartBoundary>& boundaries,
                              const HouseRules& rules) {
  const int n = static_cast<int>(parts.size());
  DisjointSets sets(parts.size());
  auto root = [&sets](int x) { return static_cast<int>(sets.root(static_cast<std::size_t>(x))); };
  auto join = [&sets](int x, int y) {
    sets.join(static_cast<std::size_t>(x), static_cast<std::size_t>(y));
  };
  std::vector<PartBoundary> valid;
  for (const PartBoundary& b : boundaries) {
    if (b.a >= 0 && b.b >= 0 && b.a < n && b.b < n && b.a != b.b && b.edges > 0) {
      valid.push_back(b);
    }
  }
  for (const PartBoundary& b : valid) {
    const double joint =
        b.length * static_cast<double>(b.continuous) / static_cast<double>(b.edges);
    if (5 * b.continuous >= 4 * b.edges && joint >= rules.min_width) join(b.a, b.b);
  }
  for (;;) {
    // Each house (by its root): its area, perimeter and outside boundary, and its boundary
    // with each other house.
    std::vector<HousePart> house(parts.size());
    for (int k = 0; k < n; ++k) {
      HousePart& h = house[static_cast<std::size_t>(root(k))];
      const HousePart& p = parts[static_cast<std::size_t>(k)];
      h.area += p.area;
      h.perimeter += p.perimeter;
      h.outside += p.outside;
    }
    std::map<std::pair<int, int>, double> between;
    for (const PartBoundary& b : valid) {
      const int x = root(b.a), y = root(b.b);
      if (x == y) {
        house[static_cast<std::size_t>(x)].perimeter -= 2.0 * b.length;  // inside the house
      } else {
        between[{std::min(x, y), std::max(x, y)}] += b.length;
      }
    }
    auto breaks_rules = [&](const HousePart& h) {
      return h.area < rules.min_area || 2.0 * h.area < rules.min_width * h.perimeter ||
             h.outside < rules.min_outside * h.perimeter;
    };
    std::vector<char> has_neighbour(parts.size(), 0);
    for (const auto& entry : between) {
      has_neighbour[static_cast<std::size_t>(entry.first.first)] = 1;
      has_neighbour[static_cast<std::size_t>(entry.first.second)] = 1;
    }
    int worst = -1;
    for (int k = 0; k < n; ++k) {
      const auto ks = static_cast<std::size_t>(k);
      if (root(k) != k || !has_neighbour[ks] || !breaks_rules(house[ks])) continue;
      if (worst < 0 || house[ks].area < house[static_cast<std::size_t>(worst)].area) worst = k;
    }
    if (worst < 0) break;
    int best = -1;
    double most = 0.0;
    for (const auto& [pair, length] : between) {
      const int other = pair.first == worst ? pair.second : pair.second == worst ? pair.first : -1;
      if (other >= 0 && (best < 0 || length > most)) {
        most = length;
        best = other;
      }
    }
    join(worst, best);
  }
  std::vector<int> out(parts.size(), -1);
  std::map<int, int> number;
  for (int k = 0; k < n; ++k) {
    out[static_cast<std::size_t>(k)] =
        number.emplace(root(k), static_cast<int>(number.size())).first->second;
  }
  return out;
}

}  // namespace csgtile::fit::detail
