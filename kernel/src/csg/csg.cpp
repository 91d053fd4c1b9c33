// CSG history: primitive leaves, Boolean nodes, and face sources composed through the
// Boolean engine's face origins.

#include "csgtile/kernel/csg.h"

#include <algorithm>
#include <set>

#include "boolean/arguments.h"
#include "boolean/fuse_groups.h"
#include "boolean/fuse_tree.h"
#include "csgtile/kernel/explorer.h"

namespace csgtile::kernel {

namespace {

CsgNodeKind node_kind(BooleanOp op) {
  switch (op) {
    case BooleanOp::Fuse:
      return CsgNodeKind::Fuse;
    case BooleanOp::Common:
      return CsgNodeKind::Common;
    case BooleanOp::Cut:
      return CsgNodeKind::Cut;
  }
  return CsgNodeKind::Fuse;
}

void sort_unique(std::vector<FaceSource>& list) {
  std::sort(list.begin(), list.end());
  list.erase(std::unique(list.begin(), list.end()), list.end());
}

/// A shape with its faces' sources, numbered in the combined tree being built.
struct Tracked {
  Shape shape;
  std::vector<std::vector<FaceSource>> sources;
};

/// Appends `model`'s nodes to `nodes` (children renumbered) and returns its shape with its
/// sources renumbered the same way.
Tracked append_tree(std::vector<CsgNode>& nodes, const CsgModel& model) {
  const int offset = static_cast<int>(nodes.size());
  for (CsgNode node : model.nodes) {
    for (int& c : node.children) c += offset;
    nodes.push_back(std::move(node));
  }
  Tracked t{model.shape, model.face_sources};
  for (auto& list : t.sources) {
    for (FaceSource& s : list) s.node += offset;
  }
  return t;
}

/// `t` ready for the engine (boolean/arguments.h): a model whose shape is a set of solids that
/// meet (op none scenes, stacked models) becomes their union, each face keeping the sources
/// of the faces it comes from.
Result<Tracked> prepared(const Tracked& t, const BooleanOptions& options) {
  auto p = detail::prepare_argument(t.shape, options);
  if (!p.ok()) return p.error();
  if (p.value().faces.empty()) return t;
  if (t.sources.empty()) return Tracked{p.value().shape, {}};  // a model without history
  Tracked out{p.value().shape, std::vector<std::vector<FaceSource>>(p.value().faces.size())};
  for (std::size_t f = 0; f < out.sources.size(); ++f) {
    for (int from : p.value().faces[f]) {
      const auto& list = t.sources.at(static_cast<std::size_t>(from));
      out.sources[f].insert(out.sources[f].end(), list.begin(), list.end());
    }
    sort_unique(out.sources[f]);
  }
  return out;
}

/// a op b on prepared arguments (and the engine's own results, which are), composing the
/// result faces' sources through the arguments'.
Result<Tracked> tracked_boolean(const Tracked& a, const Tracked& b, BooleanOp op,
                                const BooleanOptions& options) {
  std::vector<std::vector<FaceOrigin>> origins;
  auto r = detail::run_engine(a.shape, b.shape, op, options, &origins);
  if (!r.ok()) return r.error();
  Tracked out{r.value(), {}};
  out.sources.resize(origins.size());
  for (std::size_t f = 0; f < out.sources.size(); ++f) {
    for (const FaceOrigin& o : origins[f]) {
      const Tracked& from = o.operand == 0 ? a : b;
      const auto& list = from.sources.at(static_cast<std::size_t>(o.face));
      out.sources[f].insert(out.sources[f].end(), list.begin(), list.end());
    }
    sort_unique(out.sources[f]);
  }
  return out;
}

/// The face sources of `shape` looked up in pieces whose faces it reuses (same bodies).
std::vector<std::vector<FaceSource>> gather_sources(const Shape& shape,
                                                    const std::vector<Tracked>& pieces) {
  ShapeIndex known;
  std::vector<const std::vector<FaceSource>*> lists;
  for (const Tracked& p : pieces) {
    const ShapeIndex faces = map_child_shapes(p.shape, ShapeKind::Face);
    for (std::size_t i = 0; i < faces.size(); ++i) {
      const std::size_t before = known.size();
      if (known.add(faces[i]) == before) lists.push_back(&p.sources[i]);
    }
  }
  const ShapeIndex faces = map_child_shapes(shape, ShapeKind::Face);
  std::vector<std::vector<FaceSource>> out(faces.size());
  for (std::size_t i = 0; i < faces.size(); ++i) {
    const std::size_t at = known.find(faces[i]);
    if (at != ShapeIndex::npos) out[i] = *lists[at];
  }
  return out;
}

/// Left fold with the empty-intermediate rules of boolean_fold.
Result<Tracked> tracked_fold(std::vector<Tracked> items, BooleanOp op,
                             const BooleanOptions& options) {
  Tracked acc = std::move(items.front());
  for (std::size_t i = 1; i < items.size(); ++i) {
    if (map_child_shapes(acc.shape, ShapeKind::Solid).size() == 0) {
      if (op != BooleanOp::Fuse) return acc;
      acc = std::move(items[i]);
      continue;
    }
    auto r = tracked_boolean(acc, items[i], op, options);
    if (!r.ok()) return r.error();
    acc = std::move(r).value();
  }
  return acc;
}

}  // namespace

const char* csg_node_kind_name(CsgNodeKind kind) {
  switch (kind) {
    case CsgNodeKind::Primitive:
      return "primitive";
    case CsgNodeKind::Fuse:
      return "fuse";
    case CsgNodeKind::Common:
      return "common";
    case CsgNodeKind::Cut:
      return "cut";
  }
  return "unknown";
}

Result<CsgModel> csg_primitive(const PrimitiveSpec& spec, std::string label, double tolerance) {
  auto shape = build_primitive(spec, tolerance);
  if (!shape.ok()) return shape.error();
  CsgModel m;
  m.shape = shape.value();
  CsgNode node;
  node.kind = CsgNodeKind::Primitive;
  node.primitive = spec;
  node.label = std::move(label);
  m.nodes.push_back(std::move(node));
  const std::size_t faces = map_child_shapes(m.shape, ShapeKind::Face).size();
  m.face_sources.resize(faces);
  for (std::size_t i = 0; i < faces; ++i) m.face_sources[i] = {FaceSource{0, static_cast<int>(i)}};
  return m;
}

Result<CsgModel> csg_boolean(const CsgModel& a, const CsgModel& b, BooleanOp op,
                             const BooleanOptions& options) {
  CsgModel m;
  auto ta = prepared(append_tree(m.nodes, a), options);
  if (!ta.ok()) return ta.error();
  auto tb = prepared(append_tree(m.nodes, b), options);
  if (!tb.ok()) return tb.error();
  auto r = tracked_boolean(ta.value(), tb.value(), op, options);
  if (!r.ok()) return r.error();
  CsgNode node;
  node.kind = node_kind(op);
  node.children = {a.root(), static_cast<int>(a.nodes.size()) + b.root()};
  m.nodes.push_back(std::move(node));
  m.shape = r.value().shape;
  m.face_sources = std::move(r.value().sources);
  return m;
}

Result<CsgModel> csg_combine(const std::vector<CsgModel>& models, BooleanOp op,
                             const BooleanOptions& options) {
  if (models.empty()) return Error{ErrorCode::InvalidArgument, "csg_combine of no models"};
  CsgModel m;
  CsgNode node;
  node.kind = node_kind(op);
  std::vector<Tracked> items;
  for (const CsgModel& model : models) {
    auto item = prepared(append_tree(m.nodes, model), options);
    if (!item.ok()) return item.error();
    items.push_back(std::move(item).value());
    node.children.push_back(static_cast<int>(m.nodes.size()) - 1);
  }
  m.nodes.push_back(std::move(node));

  Tracked result;
  if (op != BooleanOp::Fuse) {
    auto r = tracked_fold(std::move(items), op, options);
    if (!r.ok()) return r.error();
    result = std::move(r).value();
  } else {
    std::vector<Shape> shapes;
    for (const Tracked& t : items) shapes.push_back(t.shape);
    std::vector<Tracked> pieces;
    std::vector<Shape> solids;
    for (const auto& group : detail::fuse_groups(shapes, options.tolerance)) {
      std::vector<Tracked> members;
      for (std::size_t i : group) members.push_back(items[i]);
      auto r = detail::fuse_tree(members, [&](const Tracked& x, const Tracked& y) {
        return tracked_boolean(x, y, BooleanOp::Fuse, options);
      });
      if (!r.ok()) return r.error();
      for (const Shape& s : Explorer(r.value().shape, ShapeKind::Solid)) solids.push_back(s);
      pieces.push_back(std::move(r).value());
    }
    auto compound = ShapeFactory::compound(std::move(solids));
    if (!compound.ok()) return compound.error();
    result.shape = compound.value();
    result.sources = gather_sources(result.shape, pieces);
  }
  if (result.shape.kind() != ShapeKind::Compound) {
    // A single argument of another kind: keep results uniformly compounds of solids.
    Tracked piece = result;
    auto compound = ShapeFactory::compound({result.shape});
    if (!compound.ok()) return compound.error();
    result.shape = compound.value();
    result.sources = gather_sources(result.shape, {piece});
  }
  m.shape = result.shape;
  m.face_sources = std::move(result.sources);
  return m;
}

Status check_csg(const CsgModel& model) {
  auto bad = [](const std::string& message) {
    return Status(ErrorCode::CorruptData, "CSG history: " + message);
  };
  const std::size_t n = model.nodes.size();
  if (n == 0) {
    if (!model.face_sources.empty()) return bad("face sources without a tree");
    return {};
  }
  std::vector<int> face_counts(n, -1);
  std::vector<int> parents(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    const CsgNode& node = model.nodes[i];
    const std::string name = "node " + std::to_string(i);
    if (node.kind == CsgNodeKind::Primitive) {
      if (!node.children.empty()) return bad(name + " is a primitive with children");
      auto shape = build_primitive(node.primitive);
      if (!shape.ok()) return bad(name + ": " + shape.error().message);
      face_counts[i] = static_cast<int>(map_child_shapes(shape.value(), ShapeKind::Face).size());
      continue;
    }
    if (node.children.empty()) return bad(name + " is an operation without arguments");
    for (int c : node.children) {
      if (c < 0 || static_cast<std::size_t>(c) >= i) {
        return bad(name + " has child " + std::to_string(c) + " that is not an earlier node");
      }
      ++parents[static_cast<std::size_t>(c)];
    }
  }
  for (std::size_t i = 0; i + 1 < n; ++i) {
    if (parents[i] != 1) {
      return bad("node " + std::to_string(i) + " has " + std::to_string(parents[i]) +
                 " parents (a tree gives every node but the root exactly one)");
    }
  }
  if (parents[n - 1] != 0) return bad("the root is a child");
  const std::size_t faces = map_child_shapes(model.shape, ShapeKind::Face).size();
  if (model.face_sources.size() != faces) {
    return bad(std::to_string(model.face_sources.size()) + " face source lists for " +
               std::to_string(faces) + " faces");
  }
  for (std::size_t f = 0; f < faces; ++f) {
    const auto& list = model.face_sources[f];
    if (list.empty()) return bad("face " + std::to_string(f) + " has no source");
    for (std::size_t k = 0; k < list.size(); ++k) {
      const FaceSource& s = list[k];
      if (s.node < 0 || static_cast<std::size_t>(s.node) >= n ||
          face_counts[static_cast<std::size_t>(s.node)] < 0) {
        return bad("face " + std::to_string(f) + " names node " + std::to_string(s.node) +
                   ", not a primitive");
      }
      if (s.face < 0 || s.face >= face_counts[static_cast<std::size_t>(s.node)]) {
        return bad("face " + std::to_string(f) + " names face " + std::to_string(s.face) +
                   " of node " + std::to_string(s.node) + ", which has " +
                   std::to_string(face_counts[static_cast<std::size_t>(s.node)]));
      }
      if (k > 0 && !(list[k - 1] < s)) {
        return bad("face " + std::to_string(f) + " sources are not sorted and unique");
      }
    }
  }
  return {};
}

}  // namespace csgtile::kernel
