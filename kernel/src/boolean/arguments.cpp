// Arguments of several solids: the union of their solids before the operation, with the
// history of each face of that union kept in terms of the argument's own faces.

#include "boolean/arguments.h"

#include <algorithm>
#include <map>
#include <numeric>
#include <unordered_map>

#include "boolean/fuse_groups.h"
#include "boolean/fuse_tree.h"
#include "csgtile/kernel/explorer.h"
#include "csgtile/kernel/mass_properties.h"

namespace csgtile::kernel::detail {

namespace {

// A partial union and, per face of it (child-map order), the argument faces it comes from.
struct Traced {
  Shape shape;
  std::vector<std::vector<int>> faces;
};

void sort_unique(std::vector<int>& v) {
  std::sort(v.begin(), v.end());
  v.erase(std::unique(v.begin(), v.end()), v.end());
}

}  // namespace

Result<PreparedArgument> prepare_argument(const Shape& argument, const BooleanOptions& options) {
  if (argument.is_null()) return PreparedArgument{argument, {}};
  const ShapeIndex solid_index = map_child_shapes(argument, ShapeKind::Solid);
  if (solid_index.size() < 2) return PreparedArgument{argument, {}};
  const std::vector<Shape>& solids = solid_index.shapes();
  const auto box_groups = fuse_groups(solids, options.tolerance);
  if (box_groups.size() == solids.size()) return PreparedArgument{argument, {}};
  // Within each group of meeting boxes, the solids that really meet (the engine's contact
  // test): components of that graph are what gets fused.
  std::vector<std::size_t> parent(solids.size());
  std::iota(parent.begin(), parent.end(), std::size_t{0});
  auto root = [&](std::size_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  bool any_contact = false;
  for (const auto& members : box_groups) {
    for (std::size_t i = 0; i < members.size(); ++i) {
      BoundingBox bi = bounding_box(solids[members[i]]);
      bi.enlarge(options.tolerance);
      for (std::size_t j = i + 1; j < members.size(); ++j) {
        if (!bi.intersects(bounding_box(solids[members[j]]))) continue;
        if (root(members[i]) == root(members[j])) continue;
        auto contact = run_interference(solids[members[i]], solids[members[j]], options);
        if (!contact.ok()) return contact.error();
        if (contact.value() == Interference::Disjoint) continue;
        const std::size_t ra = root(members[i]), rb = root(members[j]);
        parent[std::max(ra, rb)] = std::min(ra, rb);
        any_contact = true;
      }
    }
  }
  if (!any_contact) return PreparedArgument{argument, {}};
  std::map<std::size_t, std::vector<std::size_t>> components;  // keyed by smallest member
  for (std::size_t i = 0; i < solids.size(); ++i) components[root(i)].push_back(i);

  const ShapeIndex argument_faces = map_child_shapes(argument, ShapeKind::Face);
  auto traced_solid = [&](const Shape& solid) {
    Traced t{solid, {}};
    const ShapeIndex faces = map_child_shapes(solid, ShapeKind::Face);
    for (const Shape& f : faces.shapes())
      t.faces.push_back({static_cast<int>(argument_faces.find(f))});
    return t;
  };
  auto fuse = [&](const Traced& x, const Traced& y) -> Result<Traced> {
    std::vector<std::vector<FaceOrigin>> origins;
    auto r = run_engine(x.shape, y.shape, BooleanOp::Fuse, options, &origins);
    if (!r.ok()) return r.error();
    Traced out{r.value(), std::vector<std::vector<int>>(origins.size())};
    for (std::size_t i = 0; i < origins.size(); ++i) {
      for (const FaceOrigin& o : origins[i]) {
        const auto& from = (o.operand == 0 ? x : y).faces.at(static_cast<std::size_t>(o.face));
        out.faces[i].insert(out.faces[i].end(), from.begin(), from.end());
      }
      sort_unique(out.faces[i]);
    }
    return out;
  };

  // Each face of the union, by body and location, with its argument faces.
  std::unordered_map<Shape, std::vector<int>, ShapeSameHash, ShapeSameEqual> history;
  std::vector<Shape> parts;
  for (const auto& component : components) {
    const std::vector<std::size_t>& members = component.second;
    std::vector<Traced> group;
    for (std::size_t i : members) group.push_back(traced_solid(solids[i]));
    Traced united = group.front();
    if (group.size() > 1) {
      auto fused = fuse_tree(group, fuse);
      if (!fused.ok()) return fused.error();
      united = std::move(fused).value();
    }
    const ShapeIndex faces = map_child_shapes(united.shape, ShapeKind::Face);
    for (std::size_t i = 0; i < faces.size(); ++i) history.emplace(faces[i], united.faces.at(i));
    for (const Shape& s : Explorer(united.shape, ShapeKind::Solid)) parts.push_back(s);
  }
  auto compound = ShapeFactory::compound(std::move(parts));
  if (!compound.ok()) return compound.error();
  PreparedArgument out{compound.value(), {}};
  const ShapeIndex faces = map_child_shapes(out.shape, ShapeKind::Face);
  for (const Shape& f : faces.shapes()) out.faces.push_back(history.at(f));
  return out;
}

void restate_origins(std::vector<std::vector<FaceOrigin>>& origins, const PreparedArgument& a,
                     const PreparedArgument& b) {
  if (a.faces.empty() && b.faces.empty()) return;
  for (auto& list : origins) {
    std::vector<FaceOrigin> restated;
    for (const FaceOrigin& o : list) {
      const PreparedArgument& from = o.operand == 0 ? a : b;
      if (from.faces.empty()) {
        restated.push_back(o);
        continue;
      }
      for (int f : from.faces.at(static_cast<std::size_t>(o.face)))
        restated.push_back({o.operand, f});
    }
    std::sort(restated.begin(), restated.end());
    restated.erase(std::unique(restated.begin(), restated.end()), restated.end());
    list = std::move(restated);
  }
}

}  // namespace csgtile::kernel::detail
