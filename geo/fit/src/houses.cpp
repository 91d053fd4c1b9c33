// Houses of a block from its roof partition (see houses.h).

#include "houses.h"

#include <map>
#include <numeric>
#include <utility>

namespace csgtile::fit::detail {

namespace {

int find(std::vector<int>& parent, int x) {
  while (parent[static_cast<std::size_t>(x)] != x) {
    const auto at = static_cast<std::size_t>(x);
    parent[at] = parent[static_cast<std::size_t>(parent[at])];
    x = parent[at];
  }
  return x;
}

// Joins the sets of x and y under the lower root (a house keeps its first part's number).
void join(std::vector<int>& parent, int x, int y) {
  x = find(parent, x);
  y = find(parent, y);
  if (x == y) return;
  if (y < x) std::swap(x, y);
  parent[static_cast<std::size_t>(y)] = x;
}

}  // namespace

std::vector<int> group_houses(const std::vector<HousePart>& parts,
                              const std::vector<PartBoundary>& boundaries,
                              const HouseRules& rules) {
  const int n = static_cast<int>(parts.size());
  std::vector<int> parent(parts.size());
  std::iota(parent.begin(), parent.end(), 0);
  std::vector<PartBoundary> valid;
  for (const PartBoundary& b : boundaries) {
    if (b.a >= 0 && b.b >= 0 && b.a < n && b.b < n && b.a != b.b && b.edges > 0) {
      valid.push_back(b);
    }
  }
  for (const PartBoundary& b : valid) {
    const double joint =
        b.length * static_cast<double>(b.continuous) / static_cast<double>(b.edges);
    if (5 * b.continuous >= 4 * b.edges && joint >= rules.min_width) join(parent, b.a, b.b);
  }
  for (;;) {
    // Each house (by its root): its area, perimeter and outside boundary, and its boundary
    // with each other house.
    std::vector<HousePart> house(parts.size());
    for (int k = 0; k < n; ++k) {
      HousePart& h = house[static_cast<std::size_t>(find(parent, k))];
      const HousePart& p = parts[static_cast<std::size_t>(k)];
      h.area += p.area;
      h.perimeter += p.perimeter;
      h.outside += p.outside;
    }
    std::map<std::pair<int, int>, double> between;
    for (const PartBoundary& b : valid) {
      const int x = find(parent, b.a), y = find(parent, b.b);
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
      if (find(parent, k) != k || !has_neighbour[ks] || !breaks_rules(house[ks])) continue;
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
    join(parent, worst, best);
  }
  std::vector<int> out(parts.size(), -1);
  std::map<int, int> number;
  for (int k = 0; k < n; ++k) {
    out[static_cast<std::size_t>(k)] =
        number.emplace(find(parent, k), static_cast<int>(number.size())).first->second;
  }
  return out;
}

}  // namespace csgtile::fit::detail
